# Image error against triangles drawn: leaf-collapse LODs and meshoptimizer on the same leaves,
# from bench_foliage --dat FILE:
#   gnuplot -e "dat='build-release/bench_foliage.dat'; out='docs/img/bench_foliage.png'" scripts/plot_foliage.gp
# Columns: tree n leaves radii resolution xylem_tris xylem_rmse xylem_cover simplify_tris
#          simplify_rmse simplify_cover sloppy_tris sloppy_rmse sloppy_cover (a peer that stopped
#          short of the count: 0 triangles and -1).
if (!exists("dat")) dat = 'build-release/bench_foliage.dat'
if (!exists("out")) out = 'docs/img/bench_foliage.png'
set terminal pngcairo size 1400,600 font ",10"
set output out
set multiplot layout 1,2
set logscale x
set grid
set key top right box opaque
set xlabel "triangles drawn"
set ylabel "image RMSE, mean of the 20 views"
ok(x) = x >= 0 ? x : 1/0
do for [t in "abop-2.8-ternary random-crown"] {
    set title sprintf("%s: image RMSE at the resolution where each LOD is used", t)
    plot dat using (strcol(1) eq t ? $6 : 1/0):7 with linespoints pt 7 lc 1 title "xylem leaf collapse", \
         dat using (strcol(1) eq t ? $9 : 1/0):(ok($10)) with linespoints pt 5 lc 2 title "meshopt\\_simplify", \
         dat using (strcol(1) eq t ? $12 : 1/0):(ok($13)) with linespoints pt 9 lc 3 title "meshopt\\_simplifySloppy"
}
unset multiplot
