set terminal pngcairo size 900,520 noenhanced
set output '/work/scratch/bench-5M-50M/plots/stages.png'
set grid
set key outside
set title 'preprocess time per stage'
set style data histograms
set style histogram rowstacked
set style fill solid 0.8 border -1
set boxwidth 0.6
set ylabel 's'
plot '/work/scratch/bench-5M-50M/plots/stages.dat' using 2:xtic(1) title 'brick', '/work/scratch/bench-5M-50M/plots/stages.dat' using 3 title 'build bricks', '/work/scratch/bench-5M-50M/plots/stages.dat' using 4 title 'merge', '/work/scratch/bench-5M-50M/plots/stages.dat' using 5 title 'pack', '/work/scratch/bench-5M-50M/plots/stages.dat' using 6 title 'snap', '/work/scratch/bench-5M-50M/plots/stages.dat' using 7 title 'survey', '/work/scratch/bench-5M-50M/plots/stages.dat' using 8 title 'visibility', '/work/scratch/bench-5M-50M/plots/stages.dat' using 9 title 'write', '/work/scratch/bench-5M-50M/plots/stages.dat' using 10 title 'seams'
