if (strstrt(GPVAL_TERMINALS, 'pngcairo') > 0) {
  set terminal pngcairo size 800,520 font 'sans,10'
} else {
  set terminal png size 800,520
}
set output 'scaling.png'
set title "vsplat scaling: colin27 512x512, speedup over 1 thread (2 logical CPUs)"
set xlabel 'threads'
set ylabel 'speedup'
set xtics 1
set grid
set key top left
set xrange [0.5:4.5]
set yrange [0:*]
plot x <= 2 ? x : 2 with lines dt 2 lc rgb 'gray' title 'ideal', 'scaling.dat' index 0 using 1:3 with linespoints pt 7 title 'post-cd pinned', '' index 1 using 1:3 with linespoints pt 6 title 'post-cd unpinned', '' index 2 using 1:3 with linespoints pt 5 title 'pre pinned', '' index 3 using 1:3 with linespoints pt 4 title 'pre unpinned'
