if (strstrt(GPVAL_TERMINALS, 'pngcairo') > 0) {
  set terminal pngcairo size 800,520 font 'sans,10'
} else {
  set terminal png size 800,520
}
set output 'limits.png'
set title "vsplat stages against the limits: colin27 512x512, 2 threads (AMD EPYC, 2 logical CPUs, ISA avx512)" noenhanced
set ylabel '% of the L2 limit of one thread'
set datafile missing '-'
set style data histograms
set style histogram clustered gap 1
set style fill solid 0.8 border -1
set grid ytics
set key top right noenhanced
set yrange [0:*]
plot for [i=2:5] 'limits_plot.dat' using i:xtic(1) title columnheader(i)
