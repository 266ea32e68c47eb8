set terminal pngcairo size 900,520 noenhanced
set output '/work/scratch/bench-5M-50M/plots/preprocess.png'
set grid
set key outside
set title 'preprocess time and peak memory against model size'
set logscale x
set xlabel 'input triangles'
set ylabel 'wall s'
set y2label 'peak RSS MiB'
set ytics nomirror
set y2tics
plot '/work/scratch/bench-5M-50M/plots/preprocess.dat' using 1:2 with linespoints title 'wall s', '/work/scratch/bench-5M-50M/plots/preprocess.dat' using 1:3 axes x1y2 with linespoints title 'peak RSS MiB'
