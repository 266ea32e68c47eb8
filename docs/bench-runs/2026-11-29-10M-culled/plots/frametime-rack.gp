set terminal pngcairo size 900,520 noenhanced
set output '/work/scratch/bench-10M/plots/frametime-rack.png'
set grid
set key outside
set title 'frame time along rack, plant 10M'
set xlabel 'frame'
set ylabel 'ms'
plot '/work/scratch/bench-10M/plots/frametime-rack-reference.dat' with lines title 'reference (brute force)', '/work/scratch/bench-10M/plots/frametime-rack-lod.dat' with lines title 'LOD only', '/work/scratch/bench-10M/plots/frametime-rack-lod_frustum.dat' with lines title 'LOD + frustum', '/work/scratch/bench-10M/plots/frametime-rack-lod_frustum_occlusion.dat' with lines title 'LOD + frustum + occlusion', '/work/scratch/bench-10M/plots/frametime-rack-default.dat' with lines title 'full default'
