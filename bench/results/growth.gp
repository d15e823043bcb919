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
set xlabel 'relevant voxels, or voxels with levels of detail (sphere:N, 256^2)'
set title 'slope 0.31 full resolution, 0.22 levels of detail'
plot 'growth.dat' index 0 using 1:2 with linespoints pt 7 title 'full resolution (relevant)', 'growth.dat' index 2 using 1:2 with linespoints pt 5 title 'levels of detail (all voxels)'
set xlabel 'pixels (sphere:128)'
set title 'slope 0.49'
plot 'growth.dat' index 1 using 1:2 with linespoints pt 7 title 'frame time'
unset multiplot
