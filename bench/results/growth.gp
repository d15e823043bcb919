if (strstrt(GPVAL_TERMINALS, 'pngcairo') > 0) {
  set terminal pngcairo size 1000,450 font 'sans,10'
} else {
  set terminal png size 1000,450
}
set output 'growth.png'
set multiplot layout 1,2 title 'vsplat growth (post-cd, log-log)'
set logscale xy
set grid
set key top left
set ylabel 'frame ms'
set xlabel 'voxels (sphere:N, 256^2)'
set title 'slope 0.41 full resolution, 0.18 levels of detail'
plot 'growth.dat' index 0 using 1:2 with linespoints pt 7 title 'full resolution', 'growth.dat' index 1 using 1:2 with linespoints pt 5 title 'levels of detail'
set xlabel 'pixels'
set title 'slopes 0.51, -0.00, 0.68'
plot 'growth.dat' index 2 using 1:2 with linespoints pt 7 title 'sphere:128', 'growth.dat' index 3 using 1:2 with linespoints pt 9 title 'sphere:512, full resolution', 'growth.dat' index 4 using 1:2 with linespoints pt 5 title 'sphere:512, levels of detail'
unset multiplot
