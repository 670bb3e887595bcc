/* Twig pruning (xyl_skeleton_prune) and the chain of stem LODs built from it
 * (xyl_stems_lods_build, its pick and its glTF file). */
#include "test_util.h"
#include "xylem/xyl_foliage.h"

#include "foliage_internal.h" /* xyl__foliage_view_resolve: the pick's formula, to compare */

static xyl_skeleton *grow_preset(const char *name)
{
    return tu_grow(xyl_lsystem_preset_source(name), NULL);
}

static xyl_skeleton *skeleton_of(const xyl_skel_node *nodes, size_t count,
                                 const xyl_skel_leaf *leaves, size_t leaf_count)
{
    xyl_skeleton_desc d = {0};
    d.nodes = nodes;
    d.node_count = count;
    d.leaves = leaves;
    d.leaf_count = leaf_count;
    d.origin[0] = 1000.0;
    xyl_skeleton *sk = NULL;
    assert_int_equal(xyl_skeleton_create(&d, &sk, NULL), XYL_OK);
    return sk;
}

/* ---- pruning, checked independently ----------------------------------------------------------- */

/* The widest diameter of each node's subtree, from the definition: every node widens each of
 * its ancestors, found by walking up (O(n depth)). */
static float *subtree_widths(const xyl_skeleton *s)
{
    size_t n = s->node_count;
    float *w = calloc(n ? n : 1, sizeof *w);
    assert_non_null(w);
    for (size_t j = 0; j < n; ++j)
        for (int32_t k = (int32_t)j; k >= 0; k = s->nodes[k].parent)
            if (2.0f * s->nodes[j].radius > w[k]) w[k] = 2.0f * s->nodes[j].radius;
    return w;
}

/* The nodes that must stay, from the definition alone. */
static bool *expected_kept(const xyl_skeleton *s, float width)
{
    size_t n = s->node_count;
    bool *keep = calloc(n ? n : 1, sizeof *keep);
    assert_non_null(keep);
    float *w = subtree_widths(s);
    for (size_t i = 0; i < n; ++i) {
        float widest = w[i];
        int32_t p = s->nodes[i].parent;
        /* a root's next node: its branch continues the root's (derived branch ids) */
        bool trunk = p < 0 || (s->nodes[p].parent < 0 && s->nodes[i].branch == s->nodes[p].branch);
        keep[i] = trunk || widest >= width;
    }
    free(w);
    return keep;
}

static bool same_vec(xyl_vec3 a, xyl_vec3 b)
{
    return a.x == b.x && a.y == b.y && a.z == b.z;
}

/* Every expected node is there, in order, and nothing else; every leaf stays where it was,
 * hanging from its nearest kept ancestor; the stats add up. Returns the nodes removed. */
static size_t check_prune(const char *name, const xyl_skeleton *s, float width)
{
    bool *keep = expected_kept(s, width);
    xyl_skeleton *p = NULL;
    xyl_skeleton_prune_stats st;
    xyl_diag diag = {0};
    if (xyl_skeleton_prune(s, width, NULL, &p, &st, &diag) != XYL_OK)
        fail_msg("%s at %g: %s", name, (double)width, diag.message);
    size_t n = s->node_count, kept = 0, cuts = 0, moved = 0;
    int32_t *new_index = malloc((n ? n : 1) * sizeof *new_index);
    assert_non_null(new_index);
    float worst = 0.0f, *w = subtree_widths(s);
    for (size_t i = 0; i < n; ++i) {
        int32_t par = s->nodes[i].parent;
        if (!keep[i]) {
            new_index[i] = -1;
            if (keep[par]) {
                ++cuts;
                if (w[i] > worst) worst = w[i]; /* the widest node of the cut subtree */
            }
            continue;
        }
        if (kept >= p->node_count) fail_msg("%s at %g: too few nodes kept", name, (double)width);
        const xyl_skel_node *k = &p->nodes[kept];
        if (!same_vec(k->pos, s->nodes[i].pos) || k->radius != s->nodes[i].radius ||
            k->parent != (par < 0 ? -1 : new_index[par]))
            fail_msg("%s at %g: node %zu is not kept as it was", name, (double)width, i);
        new_index[i] = (int32_t)kept++;
    }
    if (kept != p->node_count)
        fail_msg("%s at %g: %zu nodes kept, %zu expected", name, (double)width, p->node_count,
                 kept);
    assert_int_equal(p->leaf_count, s->leaf_count);
    for (size_t j = 0; j < s->leaf_count; ++j) {
        const xyl_skel_leaf *a = &s->leaves[j], *b = &p->leaves[j];
        assert_true(same_vec(a->pos, b->pos) && same_vec(a->heading, b->heading) &&
                    same_vec(a->left, b->left) && same_vec(a->up, b->up) && a->size == b->size);
        int32_t at = a->node;
        if (at >= 0 && !keep[at]) ++moved;
        while (at >= 0 && !keep[at]) at = s->nodes[at].parent;
        if (b->node != (at < 0 ? -1 : new_index[at]))
            fail_msg("%s at %g: leaf %zu hangs from %d, not from its nearest kept ancestor", name,
                     (double)width, j, (int)b->node);
    }
    assert_int_equal(st.nodes_removed, n - kept);
    assert_int_equal(st.subtrees_removed, cuts);
    assert_int_equal(st.leaves_moved, moved);
    assert_true(st.max_removed_width == worst);
    assert_true(st.max_removed_width < width || st.nodes_removed == 0);
    assert_int_equal(p->root_count, s->root_count);
    assert_true(memcmp(p->origin, s->origin, sizeof p->origin) == 0);
    free(new_index);
    free(keep);
    free(w);
    xyl_skeleton_destroy(p);
    return n - kept;
}

static void prune_removes_exactly_the_thin_subtrees_of_every_preset(void **state)
{
    (void)state;
    for (size_t i = 0; i < xyl_lsystem_preset_count(); ++i) {
        const char *name = xyl_lsystem_preset_name(i);
        xyl_skeleton *s = grow_preset(name);
        float widest = 0.0f;
        for (size_t k = 0; k < s->node_count; ++k)
            if (2.0f * s->nodes[k].radius > widest) widest = 2.0f * s->nodes[k].radius;
        static const float fractions[] = {0.0f, 0.05f, 0.2f, 0.5f, 0.9f, 2.0f};
        size_t before = 0;
        for (size_t f = 0; f < sizeof fractions / sizeof fractions[0]; ++f) {
            size_t removed = check_prune(name, s, fractions[f] * widest);
            if (f == 0) assert_int_equal(removed, 0);
            assert_true(removed >= before); /* a wider budget never keeps more */
            before = removed;
        }
        xyl_skeleton_destroy(s);
    }
}

/* A tree 0 -> 1 -> 2 -> 3 thinning to a twig tail, a wider child 4 -> 5 of node 1 (which
 * continues the trunk), a twig 6 from node 2 with a leaf on it, a leaf on the tail. */
static const xyl_skel_node small_tree[] = {
    {{0, 0, 0}, 0.5f, -1, 0, 0},  {{0, 1, 0}, 0.4f, 0, 0, 0},   {{0, 2, 0}, 0.1f, 1, 0, 0},
    {{0, 3, 0}, 0.05f, 2, 0, 0},  {{1, 1.5f, 0}, 0.3f, 1, 0, 0}, {{2, 2, 0}, 0.2f, 4, 0, 0},
    {{-1, 2.5f, 0}, 0.02f, 2, 0, 0},
};

static const xyl_skel_leaf small_leaves[] = {
    {{-1, 2.5f, 0}, {0, 1, 0}, {1, 0, 0}, {0, 0, 1}, 0.1f, 6},
    {{0, 3, 0}, {0, 1, 0}, {1, 0, 0}, {0, 0, 1}, 0.1f, 3},
    {{0, 0.5f, 0}, {0, 1, 0}, {1, 0, 0}, {0, 0, 1}, 0.1f, -1},
};

static void prune_cuts_the_tail_and_keeps_the_trunk(void **state)
{
    (void)state;
    xyl_skeleton *s = skeleton_of(small_tree, 7, small_leaves, 3);
    xyl_skeleton *p = NULL;
    xyl_skeleton_prune_stats st;
    /* 0.25 wide: the tail 2 -> 3 (0.2 at most) and the twig 6 go; the lateral 4 (0.6) stays */
    assert_int_equal(xyl_skeleton_prune(s, 0.25f, NULL, &p, &st, NULL), XYL_OK);
    assert_int_equal(p->node_count, 4);
    assert_int_equal(st.nodes_removed, 3);
    assert_int_equal(st.subtrees_removed, 1); /* node 2 and all below it */
    assert_true(st.max_removed_width == 0.2f);
    assert_int_equal(st.leaves_moved, 2);
    assert_int_equal(p->leaves[0].node, 1); /* both hang from node 1 now, where they were */
    assert_int_equal(p->leaves[1].node, 1);
    assert_int_equal(p->leaves[2].node, -1);
    assert_true(p->leaves[0].pos.x == -1.0f && p->leaves[1].pos.y == 3.0f);
    assert_int_equal(p->branch_count, 1); /* node 4, the wider child, continued the trunk */
    assert_true(p->origin[0] == 1000.0);
    xyl_skeleton_destroy(p);
    /* wider than anything: the root and its next node alone */
    assert_int_equal(xyl_skeleton_prune(s, 100.0f, NULL, &p, &st, NULL), XYL_OK);
    assert_int_equal(p->node_count, 2);
    assert_true(same_vec(p->nodes[1].pos, small_tree[1].pos));
    assert_int_equal(p->branch_count, 1);
    assert_int_equal(st.subtrees_removed, 2); /* from node 1: the tail and the lateral */
    assert_true(st.max_removed_width == 0.6f);
    for (size_t j = 0; j < 2; ++j) assert_int_equal(p->leaves[j].node, 1);
    xyl_skeleton_destroy(p);
    /* 0: a copy */
    assert_int_equal(xyl_skeleton_prune(s, 0.0f, NULL, &p, &st, NULL), XYL_OK);
    assert_int_equal(p->node_count, 7);
    assert_int_equal(st.nodes_removed + st.subtrees_removed + st.leaves_moved, 0);
    assert_true(st.max_removed_width == 0.0f);
    xyl_skeleton_destroy(p);
    xyl_skeleton_destroy(s);
}

static void prune_keeps_every_leaf_of_a_leafy_preset(void **state)
{
    (void)state;
    xyl_skeleton *s = grow_preset("abop-2.6-monopodial");
    assert_true(s->leaf_count > 0);
    /* a width that cuts twigs with leaves: check_prune follows each leaf */
    size_t removed = check_prune("abop-2.6-monopodial", s, 2.5f * s->nodes[s->node_count - 1].radius);
    assert_true(removed > 0);
    xyl_skeleton_destroy(s);
}

static void prune_rejects_bad_input(void **state)
{
    (void)state;
    xyl_skeleton *s = skeleton_of(small_tree, 7, small_leaves, 3);
    xyl_skeleton *p = (xyl_skeleton *)(uintptr_t)1;
    xyl_skeleton_prune_stats st = {7, 7, 7.0f, 7};
    xyl_diag diag = {0};
    const float bad[] = {NAN, -1.0f, -1e-30f, INFINITY, -INFINITY};
    for (size_t i = 0; i < sizeof bad / sizeof bad[0]; ++i) {
        assert_int_equal(xyl_skeleton_prune(s, bad[i], NULL, &p, &st, &diag),
                         XYL_ERR_INVALID_ARGUMENT);
        assert_true(strstr(diag.message, "prune width") != NULL);
    }
    assert_int_equal(xyl_skeleton_prune(NULL, 1.0f, NULL, &p, &st, &diag), XYL_ERR_INVALID_ARGUMENT);
    assert_int_equal(xyl_skeleton_prune(s, 1.0f, NULL, NULL, &st, &diag), XYL_ERR_INVALID_ARGUMENT);
    /* a caller-built view whose parent comes after its child */
    xyl_skel_node broken[2] = {{{0, 0, 0}, 1.0f, 1, 0, 0}, {{0, 1, 0}, 1.0f, -1, 0, 0}};
    xyl_skeleton view = {0};
    view.nodes = broken;
    view.node_count = 2;
    assert_int_equal(xyl_skeleton_prune(&view, 1.0f, NULL, &p, &st, &diag),
                     XYL_ERR_INVALID_SKELETON);
    broken[0].parent = -1;
    broken[1].parent = 0;
    broken[1].radius = NAN;
    assert_int_equal(xyl_skeleton_prune(&view, 1.0f, NULL, &p, &st, &diag), XYL_ERR_NON_FINITE);
    assert_ptr_equal(p, (xyl_skeleton *)(uintptr_t)1);
    assert_int_equal(st.nodes_removed, 7);
    /* the allocator is honoured and every block given back */
    tu_counter c = {0, 0, 0, 0};
    xyl_skeleton_prune_desc pd = {tu_counting(&c)};
    assert_int_equal(xyl_skeleton_prune(s, 0.25f, &pd, &p, NULL, NULL), XYL_OK);
    xyl_skeleton_destroy(p);
    assert_true(c.allocs > 0 && c.allocs == c.frees);
    xyl_skeleton_destroy(s);
}

/* ---- the chain ---------------------------------------------------------------------------- */

static void assert_closed(const xyl_mesh *m, uint32_t roots, const char *what)
{
    xyl_mesh_report rep;
    assert_int_equal(xyl_mesh_check(m, NULL, &rep, NULL), XYL_OK);
    if (!rep.closed_manifold || rep.euler != 2 * (int64_t)roots || rep.components != roots)
        fail_msg("%s: closed %d euler %lld components %zu (roots %u) boundary %zu nonmanifold "
                 "%zu/%zu misoriented %zu degenerate %zu duplicate %zu",
                 what, rep.closed_manifold, (long long)rep.euler, rep.components, roots,
                 rep.boundary_edges, rep.nonmanifold_edges, rep.nonmanifold_vertices,
                 rep.misoriented_edges, rep.degenerate_faces, rep.duplicate_faces);
}

/* Along the chain: budgets and errors grow, each error under its budget, faces fall strictly;
 * every LOD is closed with no pair left at a joint. */
static void check_chain(const char *name, const xyl_skeleton *s, const xyl_stems_lods *c)
{
    assert_true(c->lod_count >= 1 && c->lod_count <= XYL_STEMS_LOD_MAX);
    for (uint32_t i = 0; i < c->lod_count; ++i) {
        const xyl_stems_lod *l = &c->lods[i];
        char what[160];
        snprintf(what, sizeof what, "%s LOD %u (budget %g, error %g, %zu faces)", name, i,
                 (double)l->budget, (double)l->error, l->face_count);
        assert_closed(l->mesh, s->root_count, what);
        if (l->stats.joint_pairs_left != 0) fail_msg("%s: pairs left at joints", what);
        assert_int_equal(l->face_count, l->mesh->quad_count + l->mesh->triangle_count);
        assert_int_equal(l->node_count + l->nodes_removed, s->node_count);
        if (!(l->error < l->budget || (l->error == 0.0f && l->nodes_removed == 0)))
            fail_msg("%s: error over its budget", what);
        if (i == 0) continue;
        const xyl_stems_lod *p = &c->lods[i - 1];
        if (!(l->budget > p->budget && l->error > p->error && l->face_count < p->face_count &&
              l->nodes_removed > p->nodes_removed))
            fail_msg("%s: not coarser than LOD %u (budget %g, error %g, %zu faces)", what, i - 1,
                     (double)p->budget, (double)p->error, p->face_count);
    }
    const xyl_stems_lod *last = &c->lods[c->lod_count - 1];
    assert_true(c->trunk_only == (last->branch_count == s->root_count));
}

/* Eye distances from 0 to far beyond the coarsest LOD's: the pick never gets finer as the eye
 * moves away, starts at LOD 0 and ends at the coarsest. */
static void check_pick_sweep(const xyl_stems_lods *c)
{
    uint32_t prev = 0, lod = 99;
    double far = 1e3 * (xyl_stems_lod_error(&c->lods[c->lod_count - 1]) + 1.0) /
                 xyl_stems_pixel_world(1.0, 0, 0);
    for (int k = 0; k <= 400; ++k) {
        double d = far * pow(10.0, (k - 400) / 50.0) * (k > 0);
        assert_int_equal(xyl_stems_lods_pick(c, xyl_stems_pixel_world(d, 0.0f, 0), 0.0f, &lod,
                                             NULL), XYL_OK);
        assert_true(lod >= prev && lod < c->lod_count);
        /* the chosen LOD is within the budget and the next one is not */
        double allowed = 0.5 * xyl_stems_pixel_world(d, 0.0f, 0);
        assert_true(lod == 0 || xyl_stems_lod_error(&c->lods[lod]) <= allowed);
        assert_true(lod + 1 == c->lod_count || !(xyl_stems_lod_error(&c->lods[lod + 1]) <= allowed));
        if (k == 0) assert_int_equal(lod, 0);
        prev = lod;
    }
    assert_int_equal(prev, c->lod_count - 1);
}

static void every_preset_gets_a_chain_of_closed_coarser_lods(void **state)
{
    (void)state;
    size_t total = 0;
    for (size_t i = 0; i < xyl_lsystem_preset_count(); ++i) {
        const char *name = xyl_lsystem_preset_name(i);
        xyl_skeleton *s = grow_preset(name);
        xyl_stems_lods *c = NULL;
        xyl_diag diag = {0};
        if (xyl_stems_lods_build(s, NULL, &c, &diag) != XYL_OK) fail_msg("%s: %s", name, diag.message);
        check_chain(name, s, c);
        check_pick_sweep(c);
        /* LOD 0 at budget 0 is the finest mesh itself */
        xyl_mesh *fine = NULL;
        assert_int_equal(xyl_stems_build(s, NULL, &fine, NULL, NULL), XYL_OK);
        const xyl_mesh *l0 = c->lods[0].mesh;
        assert_int_equal(c->lods[0].face_count, fine->quad_count + fine->triangle_count);
        assert_int_equal(l0->vertex_count, fine->vertex_count);
        assert_int_equal(l0->quad_count, fine->quad_count);
        assert_memory_equal(l0->positions, fine->positions, fine->vertex_count * sizeof(xyl_vec3));
        assert_memory_equal(l0->normals, fine->normals, fine->vertex_count * sizeof(xyl_vec3));
        assert_memory_equal(l0->quads, fine->quads, 4 * fine->quad_count * sizeof(uint32_t));
        assert_true(c->lods[0].error == 0.0f && c->lods[0].budget == 0.0f);
        xyl_mesh_destroy(fine);
        print_message("%-22s %u LODs, faces", name, c->lod_count);
        for (uint32_t k = 0; k < c->lod_count; ++k) print_message(" %zu", c->lods[k].face_count);
        print_message("%s\n", c->trunk_only ? " (trunk)" : "");
        total += c->lod_count;
        xyl_stems_lods_destroy(c);
        xyl_skeleton_destroy(s);
    }
    assert_true(total > 2 * xyl_lsystem_preset_count());
}

static void options_change_the_chain_as_documented(void **state)
{
    (void)state;
    xyl_skeleton *s = grow_preset("abop-2.8-ternary");
    xyl_stems_lods *c = NULL;
    xyl_stems_lod_desc d = {0};
    d.max_lods = 1;
    assert_int_equal(xyl_stems_lods_build(s, &d, &c, NULL), XYL_OK);
    assert_int_equal(c->lod_count, 1);
    assert_false(c->trunk_only);
    xyl_stems_lods_destroy(c);
    /* a first budget prunes LOD 0; a factor of 4 makes a shorter chain of the same span */
    xyl_stems_lods *by2 = NULL, *by4 = NULL;
    d.max_lods = XYL_STEMS_LOD_MAX;
    float thinnest = INFINITY;
    for (size_t i = 0; i < s->node_count; ++i)
        thinnest = fminf(thinnest, 2.0f * s->nodes[i].radius);
    d.first_budget = 1.5f * thinnest;
    assert_int_equal(xyl_stems_lods_build(s, &d, &by2, NULL), XYL_OK);
    d.factor = 4.0f;
    assert_int_equal(xyl_stems_lods_build(s, &d, &by4, NULL), XYL_OK);
    check_chain("ternary E0 1.5 thinnest", s, by2);
    check_chain("ternary E0 1.5 thinnest x4", s, by4);
    assert_true(by2->lods[0].nodes_removed > 0 && by2->lods[0].budget == d.first_budget);
    assert_true(by4->lod_count <= by2->lod_count);
    assert_true(by2->trunk_only && by4->trunk_only); /* run to the end */
    for (uint32_t i = 1; i < by4->lod_count; ++i)
        assert_true(by4->lods[i].budget >= 4.0f * by4->lods[i - 1].budget);
    /* the sphere holds every LOD's vertices */
    for (uint32_t i = 0; i < by2->lod_count; ++i) {
        const xyl_mesh *m = by2->lods[i].mesh;
        for (size_t v = 0; v < m->vertex_count; ++v) {
            double dx = m->positions[v].x - by2->center[0], dy = m->positions[v].y - by2->center[1],
                   dz = m->positions[v].z - by2->center[2];
            assert_true(sqrt(dx * dx + dy * dy + dz * dz) <= by2->radius);
        }
    }
    xyl_stems_lods_destroy(by2);
    xyl_stems_lods_destroy(by4);
    /* a lone stem is its own trunk: one LOD */
    static const xyl_skel_node stem[] = {{{0, 0, 0}, 0.2f, -1, 0, 0}, {{0, 1, 0}, 0.1f, 0, 0, 0},
                                         {{0, 2, 0}, 0.05f, 1, 0, 0}};
    xyl_skeleton *lone = skeleton_of(stem, 3, NULL, 0);
    assert_int_equal(xyl_stems_lods_build(lone, NULL, &c, NULL), XYL_OK);
    assert_int_equal(c->lod_count, 1);
    assert_true(c->trunk_only);
    xyl_stems_lods_destroy(c);
    xyl_skeleton_destroy(lone);
    xyl_skeleton_destroy(s);
}

/* Ring sides follow each LOD's budget (unless fixed_sides): at sides 8 every coarser LOD has
 * fewer faces than the same budget's LOD with every branch at 8, thin branches drop to 3, and
 * a branch's rings stay within the budget unless it has the most sides already. */
static void lod_ring_sides_follow_the_budget(void **state)
{
    (void)state;
    xyl_skeleton *s = grow_preset("abop-2.8-ternary");
    xyl_stems_lod_desc d = {0};
    d.stems.sides = 8;
    d.max_lods = XYL_STEMS_LOD_MAX;
    xyl_stems_lods *follow = NULL, *fixed = NULL;
    assert_int_equal(xyl_stems_lods_build(s, &d, &follow, NULL), XYL_OK);
    d.fixed_sides = true;
    assert_int_equal(xyl_stems_lods_build(s, &d, &fixed, NULL), XYL_OK);
    check_chain("ternary sides 8 following", s, follow);
    check_chain("ternary sides 8 fixed", s, fixed);
    double e8 = 0.0;
    assert_int_equal(xyl_stems_ring_error(8, false, &e8), XYL_OK);
    for (uint32_t i = 0; i < follow->lod_count; ++i) {
        const xyl_stems_lod *l = &follow->lods[i];
        const xyl_stems_lod *f = NULL;
        for (uint32_t j = 0; j < fixed->lod_count; ++j)
            if (fixed->lods[j].budget == l->budget) f = &fixed->lods[j];
        print_message("LOD %u budget %g: %zu faces, ring error %g (every branch at 8: %zu faces, "
                      "ring error %g), k = 3 on %u branches\n", i, (double)l->budget,
                      l->face_count, (double)l->ring_error, f ? f->face_count : 0,
                      f ? (double)f->ring_error : 0.0, l->stats.branches_by_sides[3]);
        if (i == 0) { /* budget 0: the caller's own sides */
            assert_non_null(f);
            assert_int_equal(l->face_count, f->face_count);
            continue;
        }
        if (f) assert_true(l->face_count < f->face_count);
        assert_true(l->stats.branches_by_sides[3] > 0);
        /* a branch below 8 sides is within the budget; one at 8 no worse than at LOD 0 */
        assert_true(l->ring_error <= fmax((double)l->budget, (double)follow->lods[0].ring_error));
    }
    /* LOD 0's rings: every branch at 8, the widest one's error */
    float widest = 0.0f;
    for (size_t i = 0; i < s->node_count; ++i) widest = fmaxf(widest, s->nodes[i].radius);
    assert_true(fabs(follow->lods[0].ring_error - widest * e8) <= 1e-6 * widest);
    xyl_stems_lods_destroy(follow);
    xyl_stems_lods_destroy(fixed);
    xyl_skeleton_destroy(s);
}

/* The pick uses foliage's view formula: at the same distance the same world size of a pixel. */
static void the_pick_sees_a_pixel_as_the_foliage_pick_does(void **state)
{
    (void)state;
    const float fovys[] = {0.0f, 0.3f, 1.2f};
    const uint32_t heights[] = {0, 720, 2160};
    for (size_t f = 0; f < 3; ++f) {
        for (size_t h = 0; h < 3; ++h) {
            xyl_foliage_view v = {{0, 0, 0}, fovys[f], heights[h], 1.0f};
            double eye[3], per_distance = 0.0;
            assert_int_equal(xyl__foliage_view_resolve(&v, eye, &per_distance, NULL), XYL_OK);
            for (double d = 0.5; d < 1e4; d *= 7.0)
                assert_true(fabs(xyl_stems_pixel_world(d, fovys[f], heights[h]) -
                                 per_distance * d) <= 1e-12 * per_distance * d);
        }
    }
    assert_true(xyl_stems_pixel_world(-3.0, 0.0f, 0) == 0.0); /* inside the sphere */
}

static void lods_reject_bad_input(void **state)
{
    (void)state;
    xyl_skeleton *s = skeleton_of(small_tree, 7, small_leaves, 3);
    xyl_stems_lods *c = (xyl_stems_lods *)(uintptr_t)1;
    xyl_diag diag = {0};
    xyl_stems_lod_desc d = {0};
    d.max_lods = XYL_STEMS_LOD_MAX + 1;
    assert_int_equal(xyl_stems_lods_build(s, &d, &c, &diag), XYL_ERR_INVALID_ARGUMENT);
    assert_true(strstr(diag.message, "max_lods") != NULL);
    d.max_lods = 0;
    const float factors[] = {1.0f, 0.5f, -2.0f, NAN, INFINITY};
    for (size_t i = 0; i < 5; ++i) {
        d.factor = factors[i];
        assert_int_equal(xyl_stems_lods_build(s, &d, &c, &diag), XYL_ERR_INVALID_ARGUMENT);
        assert_true(strstr(diag.message, "factor") != NULL);
    }
    d.factor = 0.0f;
    const float budgets[] = {-0.1f, NAN, INFINITY};
    for (size_t i = 0; i < 3; ++i) {
        d.first_budget = budgets[i];
        assert_int_equal(xyl_stems_lods_build(s, &d, &c, &diag), XYL_ERR_INVALID_ARGUMENT);
        assert_true(strstr(diag.message, "budget") != NULL);
    }
    d.first_budget = 0.0f;
    d.stems.sides = 40; /* the mesher's own error, named with its LOD */
    assert_int_equal(xyl_stems_lods_build(s, &d, &c, &diag), XYL_ERR_INVALID_ARGUMENT);
    assert_true(strstr(diag.message, "stem LOD 0") != NULL);
    assert_int_equal(xyl_stems_lods_build(NULL, NULL, &c, &diag), XYL_ERR_INVALID_ARGUMENT);
    assert_int_equal(xyl_stems_lods_build(s, NULL, NULL, &diag), XYL_ERR_INVALID_ARGUMENT);
    assert_ptr_equal(c, (xyl_stems_lods *)(uintptr_t)1);
    /* the pick */
    assert_int_equal(xyl_stems_lods_build(s, NULL, &c, NULL), XYL_OK);
    uint32_t lod = 77;
    assert_int_equal(xyl_stems_lods_pick(c, NAN, 0.5f, &lod, &diag), XYL_ERR_NON_FINITE);
    assert_int_equal(xyl_stems_lods_pick(c, 1.0, NAN, &lod, &diag), XYL_ERR_NON_FINITE);
    assert_int_equal(xyl_stems_lods_pick(c, -1.0, 0.5f, &lod, &diag), XYL_ERR_INVALID_ARGUMENT);
    assert_int_equal(xyl_stems_lods_pick(c, 1.0, -0.5f, &lod, &diag), XYL_ERR_INVALID_ARGUMENT);
    assert_int_equal(xyl_stems_lods_pick(NULL, 1.0, 0.5f, &lod, &diag), XYL_ERR_INVALID_ARGUMENT);
    assert_int_equal(xyl_stems_lods_pick(c, 1.0, 0.5f, NULL, &diag), XYL_ERR_INVALID_ARGUMENT);
    assert_int_equal(lod, 77);
    assert_int_equal(xyl_stems_lods_pick(c, INFINITY, 0.5f, &lod, &diag), XYL_OK);
    assert_int_equal(lod, c->lod_count - 1);
    /* the allocator is honoured and every block given back */
    tu_counter k = {0, 0, 0, 0};
    xyl_stems_lods *own = NULL;
    d.stems.sides = 0;
    d.stems.alloc = tu_counting(&k);
    assert_int_equal(xyl_stems_lods_build(s, &d, &own, NULL), XYL_OK);
    xyl_stems_lods_destroy(own);
    assert_true(k.allocs > 0 && k.allocs == k.frees);
    xyl_stems_lods_destroy(c);
    xyl_stems_lods_destroy(NULL);
    xyl_skeleton_destroy(s);
}

/* ---- glTF ---------------------------------------------------------------------------------- */

static void the_glb_holds_every_lod_behind_msft_lod(void **state)
{
    (void)state;
    xyl_skeleton *s = grow_preset("abop-2.8-ternary");
    xyl_stems_lod_desc d = {0};
    d.max_lods = 4;
    xyl_stems_lods *c = NULL;
    assert_int_equal(xyl_stems_lods_build(s, &d, &c, NULL), XYL_OK);
    assert_int_equal(c->lod_count, 4);
    size_t need = 0;
    assert_int_equal(xyl_stems_lods_write_glb_memory(c, NULL, NULL, 0, &need, NULL), XYL_OK);
    unsigned char *buf = malloc(need);
    assert_non_null(buf);
    xyl_diag diag = {0};
    assert_int_equal(xyl_stems_lods_write_glb_memory(c, NULL, buf, need - 1, NULL, &diag),
                     XYL_ERR_INVALID_ARGUMENT);
    size_t got = 0;
    assert_int_equal(xyl_stems_lods_write_glb_memory(c, NULL, buf, need, &got, NULL), XYL_OK);
    assert_int_equal(got, need);
    assert_memory_equal(buf, "glTF", 4);
    uint32_t json_len = (uint32_t)buf[12] | (uint32_t)buf[13] << 8 | (uint32_t)buf[14] << 16 |
                        (uint32_t)buf[15] << 24;
    char *json = malloc(json_len + 1);
    assert_non_null(json);
    memcpy(json, buf + 20, json_len);
    json[json_len] = '\0';
    assert_non_null(strstr(json, "\"extensionsUsed\":[\"MSFT_lod\"]"));
    assert_non_null(strstr(json, "\"scenes\":[{\"nodes\":[0]}]"));
    assert_non_null(strstr(json, "\"MSFT_lod\":{\"ids\":[1,2,3]}"));
    for (uint32_t i = 0; i < 4; ++i) {
        char want[96];
        snprintf(want, sizeof want, "\"name\":\"stems-lod%u\",\"mesh\":%u", i, i);
        assert_non_null(strstr(json, want));
        snprintf(want, sizeof want, "\"extras\":{\"lod\":%u,\"error_world\":", i);
        const char *at = strstr(json, want);
        assert_non_null(at);
        double e = (double)xyl_stems_lod_error(&c->lods[i]);
        assert_true(fabs(strtod(at + strlen(want), NULL) - e) <= 1e-6 * e);
    }
    free(json);
    free(buf);
    /* to a file, the validator's (XYL_GLB_SAMPLES) when set */
    const char *dir = getenv("XYL_GLB_SAMPLES");
    char path[1024];
    snprintf(path, sizeof path, "%s/lods-ternary.glb", dir ? dir : ".");
    assert_int_equal(xyl_stems_lods_write_glb_file(c, path, NULL, &diag), XYL_OK);
    FILE *f = fopen(path, "rb");
    assert_non_null(f);
    fseek(f, 0, SEEK_END);
    assert_int_equal((size_t)ftell(f), need);
    fclose(f);
    if (!dir) remove(path);
    assert_int_equal(xyl_stems_lods_write_glb_file(c, "", NULL, &diag), XYL_ERR_INVALID_ARGUMENT);
    assert_int_equal(xyl_stems_lods_write_glb_file(NULL, path, NULL, &diag),
                     XYL_ERR_INVALID_ARGUMENT);
    assert_int_equal(xyl_stems_lods_write_glb_memory(c, NULL, NULL, 0, NULL, &diag),
                     XYL_ERR_INVALID_ARGUMENT);
    xyl_stems_lods_destroy(c);
    xyl_skeleton_destroy(s);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(prune_removes_exactly_the_thin_subtrees_of_every_preset),
        cmocka_unit_test(prune_cuts_the_tail_and_keeps_the_trunk),
        cmocka_unit_test(prune_keeps_every_leaf_of_a_leafy_preset),
        cmocka_unit_test(prune_rejects_bad_input),
        cmocka_unit_test(every_preset_gets_a_chain_of_closed_coarser_lods),
        cmocka_unit_test(options_change_the_chain_as_documented),
        cmocka_unit_test(lod_ring_sides_follow_the_budget),
        cmocka_unit_test(the_pick_sees_a_pixel_as_the_foliage_pick_does),
        cmocka_unit_test(lods_reject_bad_input),
        cmocka_unit_test(the_glb_holds_every_lod_behind_msft_lod),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
