set terminal pngcairo size 900,520 noenhanced
set output '/work/scratch/bench-10M/plots/scaling-decks.png'
set grid
set key outside
set title 'median frame time against model size, decks'
set logscale x
set xlabel 'input triangles'
set ylabel 'ms'
plot '/work/scratch/bench-10M/plots/scaling-decks-reference.dat' with linespoints title 'reference (brute force)', '/work/scratch/bench-10M/plots/scaling-decks-lod.dat' with linespoints title 'LOD only', '/work/scratch/bench-10M/plots/scaling-decks-lod_frustum.dat' with linespoints title 'LOD + frustum', '/work/scratch/bench-10M/plots/scaling-decks-lod_frustum_occlusion.dat' with linespoints title 'LOD + frustum + occlusion', '/work/scratch/bench-10M/plots/scaling-decks-default.dat' with linespoints title 'full default'
