/* The stem mesher once more, with its scalar loops only (XYL_NO_SIMD) and under another name, so
 * that test_stems can check that the SSE2 loops give the same bits as the loops they stand for,
 * which targets without SSE2 run. Its files make one translation unit here, in which the
 * functions they share are static (XYL__STEMS_SHARED): this copy calls only itself, and the
 * library's mesher only the library. */
#define XYL_NO_SIMD 1
#define XYL__STEMS_SHARED static
#define xyl_stems_build xyl__stems_build_scalar
#define xyl_stems_ring_error xyl__stems_ring_error_scalar
#include "stems_fork.c"
#include "stems_normals.c"
#include "stems_rings.c"
#include "stems_tree.c"
#include "stems_build.c"
