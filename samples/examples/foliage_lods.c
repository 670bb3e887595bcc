/* foliage: a leafy tree's leaves, simplified into LODs that each draw as two ranges.
 * Grows the default preset (a broadleaf crown), shapes its leaf attachments into quads, builds
 * the leaf-collapse chain with two sectors, and picks a LOD per sector for a near and a far
 * eye under a 0.5 px budget: the far eye gets fewer leaves. */
#include <stdio.h>
#include <stdlib.h>

#include <xylem/xyl_foliage.h>
#include <xylem/xyl_lsystem.h>

static size_t leaves_drawn(const xyl_foliage *f, float distance, uint32_t lod[2])
{
    xyl_foliage_view view = {.eye = {distance, f->center.y, 0}};  /* 0.8 rad, 1080 px, 0.5 px */
    size_t drawn = 0;
    if (xyl_foliage_pick(f, &view, lod, 2, NULL)) return 0;
    for (uint32_t s = 0; s < f->sector_count; ++s) {
        const xyl_foliage_lod *l = &f->sectors[s].lods[lod[s]];
        drawn += l->a + l->c;   /* draw [base, base + a) and [base + b, base + b + c) */
    }
    return drawn;
}

int main(void)
{
    xyl_diag diag = {0};
    xyl_grammar_desc gd = {.source = xyl_lsystem_preset_source(xyl_lsystem_default_preset())};
    xyl_grammar *g = NULL;
    xyl_lstring *s = NULL;
    xyl_skeleton *sk = NULL;
    xyl_foliage *f = NULL;
    xyl_leaf *leaves = NULL;
    size_t n = 0;
    xyl_foliage_leaves_desc ld = {0};   /* aspect 0.5, no stalk, no jitter */
    xyl_result r = xyl_grammar_parse(&gd, &g, &diag);
    if (!r) r = xyl_lsystem_derive(g, NULL, &s, &diag);
    if (!r) r = xyl_lsystem_interpret(g, s, NULL, &sk, &diag);
    if (!r) r = xyl_foliage_leaves_from_skeleton(sk, &ld, NULL, 0, &n, &diag);   /* count */
    if (!r && !(leaves = malloc((n ? n : 1) * sizeof *leaves))) r = XYL_ERR_OUT_OF_MEMORY;
    if (!r) r = xyl_foliage_leaves_from_skeleton(sk, &ld, leaves, n, &n, &diag);  /* fill */
    xyl_foliage_desc fd = {.leaves = leaves, .leaf_count = n, .sectors = 2};
    if (!r) r = xyl_foliage_build(&fd, &f, &diag);
    uint32_t near_lod[2] = {0}, far_lod[2] = {0};
    size_t near = r ? 0 : leaves_drawn(f, 3 * f->radius, near_lod);
    size_t far = r ? 0 : leaves_drawn(f, 200 * f->radius, far_lod);
    if (r) fprintf(stderr, "%s: %s\n", xyl_result_string(r), diag.message);
    else
        printf("%zu leaves, %zu in the array; near eye: LODs %u/%u, %zu leaves drawn; far eye: "
               "LODs %u/%u, %zu leaves drawn\n", n, f->leaf_count, near_lod[0], near_lod[1],
               near, far_lod[0], far_lod[1], far);
    int ok = !r && n > 1000 && near > far && far > 0;
    xyl_foliage_destroy(f);
    free(leaves);
    xyl_skeleton_destroy(sk);
    xyl_lstring_destroy(s);
    xyl_grammar_destroy(g);
    return ok ? 0 : 1;
}
