# Speed against error of PN tessellation, from bench_tess --dat FILE (and FILE.front):
#   gnuplot -e "dat='build-release/bench_tess.dat'; out='docs/img/bench_tess.png'" scripts/plot_tess.gp
# Columns: k subdiv variant level triangles max_err_pct rms_err_pct normal_deg gl_inst_ms
#          gl_hw_ms vk_ms (a negative time: not measured).
if (!exists("dat")) dat = 'build-release/bench_tess.dat'
if (!exists("out")) out = 'docs/img/bench_tess.png'
set terminal pngcairo size 1400,600 font ",10"
set output out
set multiplot layout 1,2
set logscale xy
set grid
set key bottom left box opaque
set xlabel "triangles drawn for the default tree"
sub(s) = s == 0 ? "none" : (s == 1 ? "catmark" : "loop")
var(v) = v == 0 ? "pn" : (v == 1 ? "rounded" : "circle")
only(c, want, x) = (c == want) ? x : 1/0
set title "max radial error on a curved branch (% of radius)"
set ylabel "max radial error %"
plot for [s=0:2] for [v=0:2] dat using (($2 == s && $3 == v) ? $5 : 1/0):6 \
       with points pt (4 + 2 * s) ps 1.1 lc (v + 1) title sprintf("%s, %s", sub(s), var(v)), \
     dat.'.front' using 1:2 with steps lw 1.5 lc rgb "black" title "Pareto front"
set title "median time per frame (render + readback)"
set ylabel "ms per frame"
set key top left
plot dat using 5:($9 > 0 ? $9 : 1/0) with points pt 7 ps 0.8 lc 1 title "GL instanced", \
     dat using 5:($10 > 0 ? $10 : 1/0) with points pt 5 ps 0.8 lc 2 title "GL hardware (TCS/TES)", \
     dat using 5:($11 > 0 ? $11 : 1/0) with points pt 9 ps 0.8 lc 3 title "Vulkan instanced"
unset multiplot
