/* libFuzzer target for the OBJ leaf reader.
 *
 * Any bytes go to xyl_foliage_leaves_from_obj (with small limits so big inputs stay fast). A
 * rejected input must come back with a filled diag, a line for everything but a lack of memory
 * or a bad option, and the outputs untouched; an accepted one must give the same count in both
 * calls, the same leaves again, leaves that xyl_foliage_check_leaves passes and, when there are
 * few, a foliage that builds. Anything else abort()s, which libFuzzer reports as a crash.
 *
 *   ./fuzz_leaf_obj -max_total_time=60 new_corpus/ tests/data/leaves
 */
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "xylem/xyl_foliage.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

#define CAPACITY 64

static void check(int ok)
{
    if (!ok) abort();
}

static void check_rejection(xyl_result r, const xyl_diag *d, size_t count, const xyl_leaf *leaves,
                            const xyl_leaf *before)
{
    check(d->code == r && d->message[0] != '\0');
    for (const char *c = d->message; *c; ++c) check((unsigned char)*c >= 0x20);
    check(r == XYL_ERR_OUT_OF_MEMORY || d->line >= 1);
    check(count == 12345);
    check(memcmp(leaves, before, CAPACITY * sizeof *leaves) == 0);
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    static xyl_leaf leaves[CAPACITY], again[CAPACITY], before[CAPACITY];
    xyl_leaf_mesh_desc desc;
    memset(&desc, 0, sizeof desc);
    desc.limits.max_leaves = CAPACITY;
    desc.limits.max_coordinate = 1e4f;
    desc.planarity = (float)(1 + size % 4) * 0.1f; /* 0.1 .. 0.4 */
    xyl_diag diag;
    memset(&diag, 0, sizeof diag);
    memset(leaves, 0x5a, sizeof leaves);
    memcpy(before, leaves, sizeof leaves);
    const char *text = (const char *)data;
    size_t n = 12345;
    xyl_result r = xyl_foliage_leaves_from_obj(text, size, &desc, NULL, 0, &n, &diag);
    if (r != XYL_OK) {
        check_rejection(r, &diag, n, leaves, before);
        size_t m = 12345;
        xyl_diag d2;
        memset(&d2, 0, sizeof d2);
        check(xyl_foliage_leaves_from_obj(text, size, &desc, leaves, CAPACITY, &m, &d2) == r);
        check_rejection(r, &d2, m, leaves, before);
        check(d2.line == diag.line && d2.index == diag.index);
        return 0;
    }
    check(n <= CAPACITY);
    size_t m = 0, k = 0;
    check(xyl_foliage_leaves_from_obj(text, size, &desc, leaves, CAPACITY, &m, &diag) == XYL_OK);
    check(m == n);
    check(xyl_foliage_leaves_from_obj(text, size, &desc, again, n, &k, &diag) == XYL_OK);
    check(k == n && (n == 0 || memcmp(leaves, again, n * sizeof *leaves) == 0));
    check(xyl_foliage_check_leaves(leaves, n, &desc.limits, &diag) == XYL_OK);
    if (n > 0 && n <= 16) {
        xyl_foliage_desc fd;
        memset(&fd, 0, sizeof fd);
        fd.leaves = leaves;
        fd.leaf_count = n;
        fd.limits = desc.limits;
        xyl_foliage *f = NULL;
        check(xyl_foliage_build(&fd, &f, &diag) == XYL_OK);
        check(f->original_count == n);
        xyl_foliage_destroy(f);
    }
    return 0;
}
