set terminal pngcairo size 900,520 noenhanced
set output '/work/scratch/bench-10M/plots/frametime-orbit.png'
set grid
set key outside
set title 'frame time along orbit, plant 10M'
set xlabel 'frame'
set ylabel 'ms'
plot '/work/scratch/bench-10M/plots/frametime-orbit-reference.dat' with lines title 'reference (brute force)', '/work/scratch/bench-10M/plots/frametime-orbit-lod.dat' with lines title 'LOD only', '/work/scratch/bench-10M/plots/frametime-orbit-lod_frustum.dat' with lines title 'LOD + frustum', '/work/scratch/bench-10M/plots/frametime-orbit-lod_frustum_occlusion.dat' with lines title 'LOD + frustum + occlusion', '/work/scratch/bench-10M/plots/frametime-orbit-default.dat' with lines title 'full default'
