/* libFuzzer target for the .glb reader of `xylem render --mesh` (samples/cli/glb_read.cpp, tinygltf
 * underneath): any input gives a result code, never a crash or a leak; a mesh that comes back
 * is one xyl_mesh_create accepted, and it is checked for index and count consistency. */
#include <stdint.h>
#include <stdlib.h>

#include "glb_read.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    xyl_mesh *m = NULL;
    xyl_diag d = {0};
    xyl_result r = xyl_sample_read_glb(data, size, &m, &d);
    if (r != XYL_OK) {
        if (m || d.message[0] == '\0') abort(); /* failures leave out alone and say why */
        return 0;
    }
    if (!m || m->tri_view_count != 2 * m->quad_count + m->triangle_count) abort();
    for (size_t i = 0; i < 3 * m->tri_view_count; ++i)
        if (m->tri_view[i] >= m->vertex_count) abort();
    xyl_mesh_destroy(m);
    return 0;
}
