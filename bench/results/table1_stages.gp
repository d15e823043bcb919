if (strstrt(GPVAL_TERMINALS, 'pngcairo') > 0) {
  set terminal pngcairo size 1000,520 font 'sans,10'
} else {
  set terminal png size 1000,520
}
set output 'table1_stages.png'
set title "vsplat Table 1: stage times, 512x512, 1 thread (median ms)"
set style data histograms
set style histogram rowstacked
set style fill solid 0.85 border -1
set boxwidth 0.75
set ylabel 'ms'
set xtics rotate by -40 scale 0 font ',9'
set key top left
set grid ytics
plot 'table1_stages.dat' using 2:xtic(1) title 'setup', '' using 3 title 'footprint rasterization', '' using 4 title 'shading', '' using 5 title 'compositing', '' using 0:7 with points pt 7 ps 1.2 lc rgb 'black' title 'total, 2 threads'
