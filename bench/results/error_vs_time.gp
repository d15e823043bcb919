if (strstrt(GPVAL_TERMINALS, 'pngcairo') > 0) {
  set terminal pngcairo size 1500,800 font 'sans,10'
} else {
  set terminal png size 1500,800
}
set output 'error_vs_time.png'
set datafile separator ','
set multiplot layout 2,3 title "vsplat: PSNR against the reference ray caster vs frame time (* = Pareto front)"
set logscale x
set xlabel 'ms (log)'
set ylabel 'PSNR dB'
set grid
set key bottom right font ',8'
set title 'sphere'
plot 'error.csv' using (strcol(1) eq 'sphere' && strcol(4) eq 'pre' ? $8 : NaN):12 with points pt 5 ps 0.8 title 'pre', 'error.csv' using (strcol(1) eq 'sphere' && strcol(4) eq 'post-cd' ? $8 : NaN):12 with points pt 7 ps 0.8 title 'post-cd', 'error.csv' using (strcol(1) eq 'sphere' && strcol(4) eq 'post-gs' ? $8 : NaN):12 with points pt 9 ps 0.8 title 'post-gs', 'error.csv' using (strcol(1) eq 'sphere' && strcol(4) eq 'post-alpha' ? $8 : NaN):12 with points pt 13 ps 0.8 title 'post-alpha', 'error.csv' using (strcol(1) eq 'sphere' && strcol(15) eq '*' ? $8 : NaN):12 with points pt 6 ps 1.8 lc rgb 'black' title 'Pareto'
set title 'ml'
plot 'error.csv' using (strcol(1) eq 'ml' && strcol(4) eq 'pre' ? $8 : NaN):12 with points pt 5 ps 0.8 title 'pre', 'error.csv' using (strcol(1) eq 'ml' && strcol(4) eq 'post-cd' ? $8 : NaN):12 with points pt 7 ps 0.8 title 'post-cd', 'error.csv' using (strcol(1) eq 'ml' && strcol(4) eq 'post-gs' ? $8 : NaN):12 with points pt 9 ps 0.8 title 'post-gs', 'error.csv' using (strcol(1) eq 'ml' && strcol(4) eq 'post-alpha' ? $8 : NaN):12 with points pt 13 ps 0.8 title 'post-alpha', 'error.csv' using (strcol(1) eq 'ml' && strcol(15) eq '*' ? $8 : NaN):12 with points pt 6 ps 1.8 lc rgb 'black' title 'Pareto'
set title 'cube'
plot 'error.csv' using (strcol(1) eq 'cube' && strcol(4) eq 'pre' ? $8 : NaN):12 with points pt 5 ps 0.8 title 'pre', 'error.csv' using (strcol(1) eq 'cube' && strcol(4) eq 'post-cd' ? $8 : NaN):12 with points pt 7 ps 0.8 title 'post-cd', 'error.csv' using (strcol(1) eq 'cube' && strcol(4) eq 'post-gs' ? $8 : NaN):12 with points pt 9 ps 0.8 title 'post-gs', 'error.csv' using (strcol(1) eq 'cube' && strcol(4) eq 'post-alpha' ? $8 : NaN):12 with points pt 13 ps 0.8 title 'post-alpha', 'error.csv' using (strcol(1) eq 'cube' && strcol(15) eq '*' ? $8 : NaN):12 with points pt 6 ps 1.8 lc rgb 'black' title 'Pareto'
set title 'colin27'
plot 'error.csv' using (strcol(1) eq 'colin27' && strcol(4) eq 'pre' ? $8 : NaN):12 with points pt 5 ps 0.8 title 'pre', 'error.csv' using (strcol(1) eq 'colin27' && strcol(4) eq 'post-cd' ? $8 : NaN):12 with points pt 7 ps 0.8 title 'post-cd', 'error.csv' using (strcol(1) eq 'colin27' && strcol(4) eq 'post-gs' ? $8 : NaN):12 with points pt 9 ps 0.8 title 'post-gs', 'error.csv' using (strcol(1) eq 'colin27' && strcol(4) eq 'post-alpha' ? $8 : NaN):12 with points pt 13 ps 0.8 title 'post-alpha', 'error.csv' using (strcol(1) eq 'colin27' && strcol(15) eq '*' ? $8 : NaN):12 with points pt 6 ps 1.8 lc rgb 'black' title 'Pareto'
set title 'sphere-persp30'
plot 'error.csv' using (strcol(1) eq 'sphere-persp30' && strcol(4) eq 'pre' ? $8 : NaN):12 with points pt 5 ps 0.8 title 'pre', 'error.csv' using (strcol(1) eq 'sphere-persp30' && strcol(4) eq 'post-cd' ? $8 : NaN):12 with points pt 7 ps 0.8 title 'post-cd', 'error.csv' using (strcol(1) eq 'sphere-persp30' && strcol(4) eq 'post-gs' ? $8 : NaN):12 with points pt 9 ps 0.8 title 'post-gs', 'error.csv' using (strcol(1) eq 'sphere-persp30' && strcol(4) eq 'post-alpha' ? $8 : NaN):12 with points pt 13 ps 0.8 title 'post-alpha', 'error.csv' using (strcol(1) eq 'sphere-persp30' && strcol(15) eq '*' ? $8 : NaN):12 with points pt 6 ps 1.8 lc rgb 'black' title 'Pareto'
set title 'colin27-tf'
plot 'error.csv' using (strcol(1) eq 'colin27-tf' && strcol(4) eq 'pre' ? $8 : NaN):12 with points pt 5 ps 0.8 title 'pre', 'error.csv' using (strcol(1) eq 'colin27-tf' && strcol(4) eq 'post-cd' ? $8 : NaN):12 with points pt 7 ps 0.8 title 'post-cd', 'error.csv' using (strcol(1) eq 'colin27-tf' && strcol(4) eq 'post-gs' ? $8 : NaN):12 with points pt 9 ps 0.8 title 'post-gs', 'error.csv' using (strcol(1) eq 'colin27-tf' && strcol(4) eq 'post-alpha' ? $8 : NaN):12 with points pt 13 ps 0.8 title 'post-alpha', 'error.csv' using (strcol(1) eq 'colin27-tf' && strcol(15) eq '*' ? $8 : NaN):12 with points pt 6 ps 1.8 lc rgb 'black' title 'Pareto'
unset multiplot
