set terminal pngcairo size 900,520 noenhanced
set output '/work/scratch/bench-5M-50M/plots/scaling-rack.png'
set grid
set key outside
set title 'median frame time against model size, rack'
set logscale x
set xlabel 'input triangles'
set ylabel 'ms'
plot '/work/scratch/bench-5M-50M/plots/scaling-rack-reference.dat' with linespoints title 'reference (brute force)', '/work/scratch/bench-5M-50M/plots/scaling-rack-lod.dat' with linespoints title 'LOD only', '/work/scratch/bench-5M-50M/plots/scaling-rack-lod_frustum.dat' with linespoints title 'LOD + frustum', '/work/scratch/bench-5M-50M/plots/scaling-rack-lod_frustum_occlusion.dat' with linespoints title 'LOD + frustum + occlusion', '/work/scratch/bench-5M-50M/plots/scaling-rack-default.dat' with linespoints title 'full default'
