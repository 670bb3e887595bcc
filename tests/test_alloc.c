/* Allocation failure, call by call. Every public call that allocates (the GL and Vulkan backends
 * aside) runs with an allocator that fails its n-th allocation, for n = 1, 2, ... until the call
 * succeeds. Each failing run must return XYL_ERR_OUT_OF_MEMORY, leave its outputs as they were
 * and give back all it took; every run, failing or not, must take all its memory from the
 * allocator it was given.
 *
 * That last part is watched from outside the library while a call runs: malloc and its kin are
 * replaced in this program (in a sanitizer build, whose allocator owns them, its allocation
 * hooks count instead), which sees the C library's own calls too (qsort's buffer, stdio's), and
 * the default allocator's mapped blocks are caught by its cache: emptied before the call, it
 * must still be empty after. OpenSubdiv keeps its topology tables in std::vector, which xylem
 * cannot route (docs/memory.md): for the calls that subdivide, operator new is allowed, as long
 * as all of it is freed before the call returns. */
#define _POSIX_C_SOURCE 200809L
#include <dirent.h>
#include <errno.h>
#include <sys/stat.h>
#include <unistd.h>

#include "test_util.h"
#include "xyl_internal.h"
#include "xylem/xyl_foliage.h"
#include "xylem/xyl_tessellate.h"

/* ---- watching malloc ------------------------------------------------------------------------ */

typedef struct strays {
    size_t calls; /* malloc, calloc, realloc, aligned allocations made while watching */
    size_t news;  /* those made by operator new (told apart outside sanitizer builds only) */
    long live;    /* blocks of either not freed yet */
} strays;

static volatile strays seen;
static volatile bool watching;

#if SANITIZED
#include <sanitizer/allocator_interface.h>
#define WATCHES_MALLOC 1

/* The hooks cannot tell operator new from malloc: every block counts as a call. */
static void on_malloc(const volatile void *p, size_t size)
{
    (void)p, (void)size;
    if (watching) seen.calls++, seen.live++;
}

static void on_free(const volatile void *p)
{
    if (watching && p) seen.live--;
}

static void watch_install(void)
{
    __sanitizer_install_malloc_and_free_hooks(on_malloc, on_free);
}
#elif defined(__GLIBC__)
#define WATCHES_MALLOC 1
/* glibc's own entry points, which the replacements below forward to. */
extern void *__libc_malloc(size_t size);
extern void *__libc_calloc(size_t count, size_t size);
extern void *__libc_realloc(void *p, size_t size);
extern void *__libc_memalign(size_t alignment, size_t size);
extern void __libc_free(void *p);

static int in_new;

/* Exported, so that they replace the C library's for every library in the process (this
 * program is built with hidden visibility). */
#define REPLACES __attribute__((visibility("default")))

static void count_block(void)
{
    if (!watching) return;
    if (in_new) seen.news++;
    else seen.calls++;
    seen.live++;
}

REPLACES void *malloc(size_t size)
{
    count_block();
    return __libc_malloc(size);
}

REPLACES void *calloc(size_t count, size_t size)
{
    count_block();
    return __libc_calloc(count, size);
}

REPLACES void *realloc(void *p, size_t size)
{
    count_block(); /* any call of it is a stray one; live counts are moot then */
    return __libc_realloc(p, size);
}

REPLACES void *aligned_alloc(size_t alignment, size_t size)
{
    count_block();
    return __libc_memalign(alignment, size);
}

REPLACES int posix_memalign(void **out, size_t alignment, size_t size)
{
    count_block();
    void *p = __libc_memalign(alignment, size);
    if (!p) return ENOMEM;
    *out = p;
    return 0;
}

void *memalign(size_t alignment, size_t size);
REPLACES void *memalign(size_t alignment, size_t size)
{
    count_block();
    return __libc_memalign(alignment, size);
}

REPLACES void free(void *p)
{
    if (watching && p) seen.live--;
    __libc_free(p);
}

/* operator new and new[], plain and nothrow (Itanium C++ ABI names): the C++ runtime's are
 * replaced too, so that OpenSubdiv's blocks are told from the library's own. The runtime's
 * operator delete frees them with free. */
static void *new_block(size_t size, bool nothrow)
{
    ++in_new;
    void *p = malloc(size ? size : 1);
    --in_new;
    if (!p && !nothrow) abort(); /* C cannot throw std::bad_alloc; never happens here */
    return p;
}

void *_Znwm(size_t size);
void *_Znam(size_t size);
void *_ZnwmRKSt9nothrow_t(size_t size, const void *tag);
void *_ZnamRKSt9nothrow_t(size_t size, const void *tag);
REPLACES void *_Znwm(size_t size)
{
    return new_block(size, false);
}
REPLACES void *_Znam(size_t size)
{
    return new_block(size, false);
}
REPLACES void *_ZnwmRKSt9nothrow_t(size_t size, const void *tag)
{
    (void)tag;
    return new_block(size, true);
}
REPLACES void *_ZnamRKSt9nothrow_t(size_t size, const void *tag)
{
    (void)tag;
    return new_block(size, true);
}
#else
#define WATCHES_MALLOC 0 /* nothing to forward to: only the allocator's own counts are checked */
#endif

#if !SANITIZED
static void watch_install(void)
{
}
#endif

static size_t mapped_before;

static void watch_begin(void)
{
    xyl_memory_trim();
    mapped_before = xyl__alloc_blocks_in_use();
    seen.calls = seen.news = 0;
    seen.live = 0;
    watching = true;
}

/* Mapped blocks of the default allocator the call took: still held, or freed into the cache. */
static size_t watch_end(strays *s)
{
    watching = false;
    *s = seen;
    size_t held = xyl__alloc_blocks_in_use() - mapped_before;
    return held + (xyl_memory_trim() > 0);
}

/* The counting allocator's own malloc is not the call's. */
static void *watched_alloc(size_t size, void *user)
{
    bool was = watching;
    watching = false;
    void *p = tu_count_alloc(size, user);
    watching = was;
    return p;
}

static void watched_free(void *p, void *user)
{
    bool was = watching;
    watching = false;
    tu_count_free(p, user);
    watching = was;
}

/* ---- the walk ------------------------------------------------------------------------------- */

/* One public call with allocator a. On success it frees what it made (with the call's destroy,
 * so that is watched too); on failure it asserts that its outputs are untouched. */
typedef xyl_result (*call_fn)(const xyl_allocator *a);

typedef struct walk_case {
    const char *name;
    call_fn run;
    bool opensubdiv; /* operator new is OpenSubdiv's, inside the call */
    bool allocates;  /* false: the call must not allocate at all */
} walk_case;

/* Runs w with the n-th allocation failing, n = 1, 2, ... until it succeeds; returns the number
 * of allocations of the successful run, each of which was made to fail once, and in *foreign
 * the blocks operator new gave OpenSubdiv in it (0 where they cannot be told apart). */
static size_t walk(const walk_case *w, size_t *foreign)
{
    for (size_t n = 1;; ++n) {
        tu_counter c = {0, 0, 0, n};
        xyl_allocator a = {watched_alloc, watched_free, &c};
        strays s;
        watch_begin();
        xyl_result r = w->run(&a);
        size_t mapped = watch_end(&s);
        size_t own = w->opensubdiv ? (SANITIZED ? 0 : s.calls) : s.calls + s.news;
        if (own || mapped || s.live)
            fail_msg("%s, allocation %zu failing: %zu blocks from malloc and %zu from operator "
                     "new behind the allocator, %ld of them not freed, %zu mapped blocks of "
                     "the default allocator", w->name, n, s.calls, s.news, s.live, mapped);
        if (c.allocs != c.frees)
            fail_msg("%s, allocation %zu failing: %zu blocks taken, %zu given back", w->name, n,
                     c.allocs, c.frees);
        if (r == XYL_OK) {
            if (c.attempts >= n)
                fail_msg("%s succeeded although its allocation %zu failed", w->name, n);
            if (w->allocates != (c.attempts > 0))
                fail_msg("%s made %zu allocations", w->name, c.attempts);
            *foreign = s.news;
            return c.attempts;
        }
        if (r != XYL_ERR_OUT_OF_MEMORY)
            fail_msg("%s, allocation %zu failing: %s", w->name, n, xyl_result_string(r));
        if (c.attempts < n)
            fail_msg("%s failed with %s before allocation %zu", w->name, xyl_result_string(r), n);
    }
}

/* ---- inputs, made once with the default allocator -------------------------------------------- */

static struct {
    const char *source;          /* grammar text */
    xyl_grammar *grammar;
    xyl_lstring *string;
    xyl_skeleton *skeleton;      /* small, for the skeleton calls and the unchecked build */
    xyl_skeleton *crowded;       /* whose checked build (k = 5) moves a lateral, builds again */
    char *skel_text;
    size_t skel_len;
    char dir[64];                /* in.skel, and out/ for the files the writers make */
    char skel_path[96], out_dir[80], out_path[96];
    xyl_mesh *mesh;              /* a stem mesh with UV seams */
    xyl_stems_lods *lods;        /* a chain of stem LODs of skeleton */
    size_t obj_size, glb_size;   /* its files' sizes */
    unsigned char *buffer;       /* room for either */
    xyl_tess_patches *patches;
    xyl_tess_patterns *patterns;
    xyl_tess_batches *batches;
    xyl_foliage *foliage;        /* a few leaves in two sectors */
    size_t leafy_size;           /* its .glb with the stem mesh */
    unsigned char *leafy;        /* room for it */
} in;

/* A recognisable non-NULL value that a failing call must leave in its *out. */
static char untouched;
#define UNTOUCHED ((void *)&untouched)

static xyl_skeleton *grow(const char *name, uint32_t depth)
{
    xyl_grammar *g = tu_parse(xyl_lsystem_preset_source(name));
    xyl_derive_desc dd = {0};
    dd.has_depth = true;
    dd.depth = depth;
    xyl_lstring *s = NULL;
    xyl_skeleton *sk = NULL;
    assert_int_equal(xyl_lsystem_derive(g, &dd, &s, NULL), XYL_OK);
    assert_int_equal(xyl_lsystem_interpret(g, s, NULL, &sk, NULL), XYL_OK);
    xyl_lstring_destroy(s);
    xyl_grammar_destroy(g);
    return sk;
}

static size_t files_in(const char *path)
{
    DIR *d = opendir(path);
    assert_non_null(d);
    size_t n = 0;
    for (struct dirent *e; (e = readdir(d)) != NULL;) n += e->d_name[0] != '.';
    closedir(d);
    return n;
}

static int setup(void **state)
{
    (void)state;
    watch_install();
    in.source = xyl_lsystem_preset_source(xyl_lsystem_default_preset());
    in.grammar = tu_parse(in.source);
    xyl_derive_desc dd = {0};
    dd.has_depth = true;
    dd.depth = 2;
    assert_int_equal(xyl_lsystem_derive(in.grammar, &dd, &in.string, NULL), XYL_OK);
    assert_int_equal(xyl_lsystem_interpret(in.grammar, in.string, NULL, &in.skeleton, NULL),
                     XYL_OK);
    in.crowded = grow("abop-1.24b", 3);
    assert_int_equal(xyl_skeleton_write_text(in.skeleton, XYL_SKEL_FORMAT_SKEL, NULL, 0,
                                             &in.skel_len), XYL_OK);
    in.skel_text = malloc(in.skel_len + 1);
    assert_non_null(in.skel_text);
    assert_int_equal(xyl_skeleton_write_text(in.skeleton, XYL_SKEL_FORMAT_SKEL, in.skel_text,
                                             in.skel_len + 1, NULL), XYL_OK);
    snprintf(in.dir, sizeof in.dir, "xyl-alloc-XXXXXX"); /* in the test's working folder */
    assert_non_null(mkdtemp(in.dir));
    snprintf(in.skel_path, sizeof in.skel_path, "%s/in.skel", in.dir);
    snprintf(in.out_dir, sizeof in.out_dir, "%s/out", in.dir);
    snprintf(in.out_path, sizeof in.out_path, "%s/tree", in.out_dir);
    assert_int_equal(xyl_skeleton_write_file(in.skeleton, in.skel_path, XYL_SKEL_FORMAT_SKEL, NULL,
                                             NULL), XYL_OK);
    assert_int_equal(mkdir(in.out_dir, 0700), 0);
    xyl_stems_desc sd = {0};
    sd.joints = XYL_JOINTS_UNCHECKED;
    assert_int_equal(xyl_stems_build(in.skeleton, &sd, &in.mesh, NULL, NULL), XYL_OK);
    xyl_stems_lod_desc ld = {0};
    ld.stems = sd;
    ld.max_lods = 3;
    assert_int_equal(xyl_stems_lods_build(in.skeleton, &ld, &in.lods, NULL), XYL_OK);
    assert_true(in.lods->lod_count >= 2); /* a glTF file with MSFT_lod */
    assert_int_equal(xyl_mesh_write_memory(in.mesh, XYL_MESH_FORMAT_OBJ, NULL, NULL, 0,
                                           &in.obj_size), XYL_OK);
    assert_int_equal(xyl_mesh_write_memory(in.mesh, XYL_MESH_FORMAT_GLB, NULL, NULL, 0,
                                           &in.glb_size), XYL_OK);
    in.buffer = malloc((in.obj_size > in.glb_size ? in.obj_size : in.glb_size) + 1);
    assert_non_null(in.buffer);
    assert_int_equal(xyl_tess_patches_create(in.mesh, NULL, &in.patches, NULL), XYL_OK);
    assert_int_equal(xyl_tess_patterns_create(4, NULL, &in.patterns, NULL), XYL_OK);
    xyl_tess_view v = {0};
    v.fixed_level = 2;
    assert_int_equal(xyl_tess_batches_create(NULL, &in.batches, NULL), XYL_OK);
    assert_int_equal(xyl_tess_select(in.patches, in.patterns, &v, in.batches, NULL), XYL_OK);
    xyl_leaf leaves[6];
    memset(leaves, 0, sizeof leaves);
    for (int i = 0; i < 6; ++i) {
        leaves[i].center = (xyl_vec3){(float)(i % 3) - 1.0f, 1.0f + 0.5f * (float)i, (float)(i / 3)};
        leaves[i].normal = (xyl_vec3){0, 0, 1};
        leaves[i].axis = (xyl_vec3){0, 0.2f, 0};
        leaves[i].side = (xyl_vec3){0.1f, 0, 0};
        leaves[i].node = -1;
    }
    xyl_foliage_desc fd = {0};
    fd.leaves = leaves;
    fd.leaf_count = 6;
    fd.sectors = 2;
    assert_int_equal(xyl_foliage_build(&fd, &in.foliage, NULL), XYL_OK);
    xyl_foliage_glb_desc gd = {0};
    gd.stems = in.mesh;
    assert_int_equal(xyl_foliage_write_glb_memory(in.foliage, &gd, NULL, 0, &in.leafy_size, NULL),
                     XYL_OK);
    in.leafy = malloc(in.leafy_size);
    assert_non_null(in.leafy);
    return 0;
}

static int teardown(void **state)
{
    (void)state;
    xyl_foliage_destroy(in.foliage);
    free(in.leafy);
    xyl_tess_batches_destroy(in.batches);
    xyl_tess_patterns_destroy(in.patterns);
    xyl_tess_patches_destroy(in.patches);
    xyl_mesh_destroy(in.mesh);
    xyl_stems_lods_destroy(in.lods);
    free(in.buffer);
    free(in.skel_text);
    xyl_skeleton_destroy(in.crowded);
    xyl_skeleton_destroy(in.skeleton);
    xyl_lstring_destroy(in.string);
    xyl_grammar_destroy(in.grammar);
    unlink(in.skel_path);
    rmdir(in.out_dir);
    rmdir(in.dir);
    return 0;
}

/* ---- l-systems -------------------------------------------------------------------------------- */

static xyl_result grammar_parse(const xyl_allocator *a)
{
    xyl_grammar_desc d = {0};
    d.source = in.source;
    d.alloc = *a;
    xyl_grammar *g = UNTOUCHED;
    xyl_diag diag = {0};
    xyl_result r = xyl_grammar_parse(&d, &g, &diag);
    if (r == XYL_OK) xyl_grammar_destroy(g);
    else assert_ptr_equal(g, UNTOUCHED);
    return r;
}

static xyl_result lsystem_derive(const xyl_allocator *a)
{
    xyl_derive_desc d = {0};
    d.has_depth = true;
    d.depth = 2;
    d.alloc = *a;
    xyl_lstring *s = UNTOUCHED;
    xyl_diag diag = {0};
    xyl_result r = xyl_lsystem_derive(in.grammar, &d, &s, &diag);
    if (r == XYL_OK) xyl_lstring_destroy(s);
    else assert_ptr_equal(s, UNTOUCHED);
    return r;
}

static xyl_result interpret(const xyl_allocator *a, xyl_angle_mode angles)
{
    xyl_turtle_desc d = {0};
    d.angle_mode = angles;
    d.alloc = *a;
    xyl_skeleton *sk = UNTOUCHED;
    xyl_diag diag = {0};
    xyl_result r = xyl_lsystem_interpret(in.grammar, in.string, &d, &sk, &diag);
    if (r == XYL_OK) xyl_skeleton_destroy(sk);
    else assert_ptr_equal(sk, UNTOUCHED);
    return r;
}

static xyl_result interpret_pipe(const xyl_allocator *a)
{
    return interpret(a, XYL_ANGLES_GRAMMAR);
}

static xyl_result interpret_murray(const xyl_allocator *a)
{
    return interpret(a, XYL_ANGLES_MURRAY);
}

/* ---- skeletons ------------------------------------------------------------------------------ */

static xyl_result skeleton_done(xyl_result r, xyl_skeleton *sk)
{
    if (r == XYL_OK) xyl_skeleton_destroy(sk);
    else assert_ptr_equal(sk, UNTOUCHED);
    return r;
}

static xyl_result skeleton_create(const xyl_allocator *a)
{
    xyl_skeleton_desc d = {0};
    d.nodes = in.skeleton->nodes;
    d.node_count = in.skeleton->node_count;
    d.leaves = in.skeleton->leaves;
    d.leaf_count = in.skeleton->leaf_count;
    d.alloc = *a;
    xyl_skeleton *sk = UNTOUCHED;
    xyl_diag diag = {0};
    xyl_result r = xyl_skeleton_create(&d, &sk, &diag);
    return skeleton_done(r, sk);
}

static xyl_result skeleton_read_text(const xyl_allocator *a)
{
    xyl_skeleton_read_desc d = {0};
    d.alloc = *a;
    xyl_skeleton *sk = UNTOUCHED;
    xyl_diag diag = {0};
    xyl_result r = xyl_skeleton_read_text(in.skel_text, in.skel_len, &d, &sk, &diag);
    return skeleton_done(r, sk);
}

static xyl_result skeleton_read_file(const xyl_allocator *a)
{
    xyl_skeleton_read_desc d = {0};
    d.alloc = *a;
    xyl_skeleton *sk = UNTOUCHED;
    xyl_diag diag = {0};
    xyl_result r = xyl_skeleton_read_file(in.skel_path, &d, &sk, &diag);
    return skeleton_done(r, sk);
}

/* A written file is removed again; a failed write must leave no file, temporary or not. The
 * look into the folder is the test's, not the call's (opendir takes memory from malloc). */
static xyl_result file_written(xyl_result r)
{
    bool was = watching;
    watching = false;
    assert_int_equal(files_in(in.out_dir), r == XYL_OK);
    if (r == XYL_OK) assert_int_equal(unlink(in.out_path), 0);
    watching = was;
    return r;
}

static xyl_result skeleton_write_skel(const xyl_allocator *a)
{
    xyl_diag diag = {0};
    return file_written(
        xyl_skeleton_write_file(in.skeleton, in.out_path, XYL_SKEL_FORMAT_SKEL, a, &diag));
}

static xyl_result skeleton_write_obj(const xyl_allocator *a)
{
    xyl_diag diag = {0};
    return file_written(
        xyl_skeleton_write_file(in.skeleton, in.out_path, XYL_SKEL_FORMAT_OBJ, a, &diag));
}

/* Takes no allocator, and needs none: the walk holds it to that. */
static xyl_result skeleton_write_text(const xyl_allocator *a)
{
    (void)a;
    size_t n = 0;
    return xyl_skeleton_write_text(in.skeleton, XYL_SKEL_FORMAT_SKEL, NULL, 0, &n);
}

/* ---- stems ---------------------------------------------------------------------------------- */

static xyl_result stems_build(const xyl_allocator *a, const xyl_skeleton *sk, uint32_t sides,
                              xyl_joint_check joints, xyl_subdivision sub)
{
    xyl_stems_desc d = {0};
    d.sides = sides;
    d.joints = joints;
    d.subdivision = sub;
    d.alloc = *a;
    xyl_mesh *m = UNTOUCHED;
    xyl_stems_stats stats, before;
    memset(&stats, 0xA5, sizeof stats);
    before = stats;
    xyl_diag diag = {0};
    xyl_result r = xyl_stems_build(sk, &d, &m, &stats, &diag);
    if (r == XYL_OK) {
        if (joints == XYL_JOINTS_CHECKED) assert_true(stats.builds > 1);
        xyl_mesh_destroy(m);
    } else {
        assert_ptr_equal(m, UNTOUCHED);
        assert_memory_equal(&stats, &before, sizeof stats);
    }
    return r;
}

static xyl_result stems_unchecked(const xyl_allocator *a)
{
    return stems_build(a, in.skeleton, 4, XYL_JOINTS_UNCHECKED, XYL_SUBDIVIDE_NONE);
}

static xyl_result stems_checked(const xyl_allocator *a)
{
    return stems_build(a, in.crowded, 5, XYL_JOINTS_CHECKED, XYL_SUBDIVIDE_NONE);
}

#if defined(XYL_HAVE_OPENSUBDIV)
static xyl_result stems_catmark(const xyl_allocator *a)
{
    return stems_build(a, in.skeleton, 4, XYL_JOINTS_UNCHECKED, XYL_SUBDIVIDE_CATMARK);
}
#endif

/* ---- twig pruning and stem LODs -------------------------------------------------------------- */

static xyl_result skeleton_prune(const xyl_allocator *a)
{
    xyl_skeleton_prune_desc d = {*a};
    xyl_skeleton *sk = UNTOUCHED;
    xyl_skeleton_prune_stats st = {5, 5, 5.0f, 5};
    xyl_diag diag = {0};
    /* half the trunk's width: some twigs go, and their leaves move */
    xyl_result r = xyl_skeleton_prune(in.skeleton, in.skeleton->nodes[0].radius, &d, &sk, &st,
                                      &diag);
    if (r == XYL_OK) assert_true(st.nodes_removed > 0);
    else assert_int_equal(st.nodes_removed, 5);
    return skeleton_done(r, sk);
}

static xyl_result stems_lods(const xyl_allocator *a)
{
    xyl_stems_lod_desc d = {0};
    d.stems.joints = XYL_JOINTS_UNCHECKED;
    d.stems.alloc = *a;
    d.max_lods = 3;
    xyl_stems_lods *c = UNTOUCHED;
    xyl_diag diag = {0};
    xyl_result r = xyl_stems_lods_build(in.skeleton, &d, &c, &diag);
    if (r == XYL_OK) xyl_stems_lods_destroy(c);
    else assert_ptr_equal(c, UNTOUCHED);
    return r;
}

/* Count, then fill; a failed pass leaves *size alone. */
static xyl_result stems_lods_glb_memory(const xyl_allocator *a)
{
    size_t size = 3;
    xyl_diag diag = {0};
    xyl_result r = xyl_stems_lods_write_glb_memory(in.lods, a, NULL, 0, &size, &diag);
    if (r != XYL_OK) {
        assert_int_equal(size, 3);
        return r;
    }
    bool was = watching; /* the caller's buffer is not the call's memory */
    watching = false;
    unsigned char *buf = malloc(size);
    watching = was;
    assert_non_null(buf);
    size_t again = 3;
    r = xyl_stems_lods_write_glb_memory(in.lods, a, buf, size, &again, &diag);
    assert_int_equal(again, r == XYL_OK ? size : 3);
    watching = false;
    free(buf);
    watching = was;
    return r;
}

static xyl_result stems_lods_glb_file(const xyl_allocator *a)
{
    xyl_diag diag = {0};
    return file_written(xyl_stems_lods_write_glb_file(in.lods, in.out_path, a, &diag));
}

/* ---- meshes --------------------------------------------------------------------------------- */

static xyl_result mesh_done(xyl_result r, xyl_mesh *m)
{
    if (r == XYL_OK) xyl_mesh_destroy(m);
    else assert_ptr_equal(m, UNTOUCHED);
    return r;
}

static xyl_result mesh_create(const xyl_allocator *a)
{
    const xyl_mesh *s = in.mesh;
    xyl_mesh_desc d = {0};
    d.positions = s->positions, d.normals = s->normals, d.uvs = s->uvs;
    d.branch_ids = s->branch_ids, d.vertex_count = s->vertex_count;
    d.quads = s->quads, d.quad_count = s->quad_count;
    d.triangles = s->triangles, d.triangle_count = s->triangle_count;
    d.face_branches = s->face_branches, d.uv_wraps = s->uv_wraps;
    d.alloc = *a;
    xyl_mesh *m = UNTOUCHED;
    xyl_diag diag = {0};
    xyl_result r = xyl_mesh_create(&d, &m, &diag);
    return mesh_done(r, m);
}

static xyl_result mesh_check(const xyl_allocator *a)
{
    xyl_mesh_report rep, before;
    memset(&rep, 0xA5, sizeof rep);
    before = rep;
    xyl_diag diag = {0};
    xyl_result r = xyl_mesh_check(in.mesh, a, &rep, &diag);
    if (r == XYL_OK) assert_true(rep.closed_manifold);
    else assert_memory_equal(&rep, &before, sizeof rep);
    return r;
}

static xyl_result mesh_self_intersections(const xyl_allocator *a)
{
    uint32_t pairs[8];
    memset(pairs, 0xA5, sizeof pairs);
    size_t count = 77;
    xyl_diag diag = {0};
    xyl_result r = xyl_mesh_self_intersections(in.mesh, a, pairs, 4, &count, &diag);
    if (r != XYL_OK) {
        assert_int_equal(count, 77);
        for (size_t i = 0; i < 8; ++i) assert_int_equal(pairs[i], 0xA5A5A5A5u);
    }
    return r;
}

static xyl_result mesh_split_seams(const xyl_allocator *a)
{
    xyl_mesh *m = UNTOUCHED;
    xyl_diag diag = {0};
    xyl_result r = xyl_mesh_split_seams(in.mesh, a, &m, &diag);
    return mesh_done(r, m);
}

#if defined(XYL_HAVE_OPENSUBDIV)
static xyl_result mesh_subdivide(const xyl_allocator *a, xyl_subdivision scheme)
{
    xyl_subdivide_desc d = {0};
    d.scheme = scheme;
    d.alloc = *a;
    xyl_mesh *m = UNTOUCHED;
    xyl_diag diag = {0};
    xyl_result r = xyl_mesh_subdivide(in.mesh, &d, &m, &diag);
    return mesh_done(r, m);
}

static xyl_result mesh_subdivide_catmark(const xyl_allocator *a)
{
    return mesh_subdivide(a, XYL_SUBDIVIDE_CATMARK);
}

static xyl_result mesh_subdivide_loop(const xyl_allocator *a)
{
    return mesh_subdivide(a, XYL_SUBDIVIDE_LOOP);
}
#endif

/* The count pass and the fill pass; a failed one leaves *needed and the buffer alone. */
static xyl_result write_memory(const xyl_allocator *a, xyl_mesh_format format)
{
    size_t size = format == XYL_MESH_FORMAT_OBJ ? in.obj_size : in.glb_size;
    size_t needed = 3, room = size + 1;
    memset(in.buffer, 0xA5, room);
    xyl_result r = xyl_mesh_write_memory(in.mesh, format, a, NULL, 0, &needed);
    if (r == XYL_OK) assert_int_equal(needed, size);
    else assert_int_equal(needed, 3);
    needed = 3;
    if (r == XYL_OK) r = xyl_mesh_write_memory(in.mesh, format, a, in.buffer, room, &needed);
    if (r != XYL_OK) {
        for (size_t i = 0; i < room; ++i) assert_int_equal(in.buffer[i], 0xA5);
        assert_int_equal(needed, 3);
    }
    return r;
}

static xyl_result write_memory_obj(const xyl_allocator *a)
{
    return write_memory(a, XYL_MESH_FORMAT_OBJ);
}

static xyl_result write_memory_glb(const xyl_allocator *a)
{
    return write_memory(a, XYL_MESH_FORMAT_GLB);
}

static xyl_result write_file_obj(const xyl_allocator *a)
{
    xyl_diag diag = {0};
    return file_written(xyl_mesh_write_file(in.mesh, in.out_path, XYL_MESH_FORMAT_OBJ, a, &diag));
}

static xyl_result write_file_glb(const xyl_allocator *a)
{
    xyl_diag diag = {0};
    return file_written(xyl_mesh_write_file(in.mesh, in.out_path, XYL_MESH_FORMAT_GLB, a, &diag));
}

/* ---- foliage export: the stems' seam split is what allocates ---------------------------------- */

/* Count, then fill; a failed pass leaves *size and the buffer alone. */
static xyl_result foliage_glb_memory(const xyl_allocator *a, const xyl_mesh *stems)
{
    xyl_foliage_glb_desc gd = {0};
    gd.stems = stems;
    gd.alloc = *a;
    xyl_diag diag = {0};
    size_t size = 3;
    memset(in.leafy, 0xA5, in.leafy_size);
    xyl_result r = xyl_foliage_write_glb_memory(in.foliage, &gd, NULL, 0, &size, &diag);
    if (r != XYL_OK) {
        assert_int_equal(size, 3);
        return r;
    }
    if (stems) assert_int_equal(size, in.leafy_size);
    r = xyl_foliage_write_glb_memory(in.foliage, &gd, in.leafy, in.leafy_size, NULL, &diag);
    if (r != XYL_OK)
        for (size_t i = 0; i < in.leafy_size; ++i) assert_int_equal(in.leafy[i], 0xA5);
    return r;
}

static xyl_result foliage_glb_memory_stems(const xyl_allocator *a)
{
    return foliage_glb_memory(a, in.mesh);
}

static xyl_result foliage_glb_memory_leaves(const xyl_allocator *a)
{
    return foliage_glb_memory(a, NULL);
}

static xyl_result foliage_glb_file(const xyl_allocator *a)
{
    xyl_foliage_glb_desc gd = {0};
    gd.stems = in.mesh;
    gd.alloc = *a;
    xyl_diag diag = {0};
    return file_written(xyl_foliage_write_glb_file(in.foliage, &gd, in.out_path, &diag));
}

/* ---- tessellation --------------------------------------------------------------------------- */

static xyl_result tess_patches(const xyl_allocator *a)
{
    xyl_tess_patches_desc d = {0};
    d.alloc = *a;
    xyl_tess_patches *tp = UNTOUCHED;
    xyl_diag diag = {0};
    xyl_result r = xyl_tess_patches_create(in.mesh, &d, &tp, &diag);
    if (r == XYL_OK) xyl_tess_patches_destroy(tp);
    else assert_ptr_equal(tp, UNTOUCHED);
    return r;
}

static xyl_result tess_patterns(const xyl_allocator *a)
{
    xyl_tess_patterns *p = UNTOUCHED;
    xyl_diag diag = {0};
    xyl_result r = xyl_tess_patterns_create(4, a, &p, &diag);
    if (r == XYL_OK) xyl_tess_patterns_destroy(p);
    else assert_ptr_equal(p, UNTOUCHED);
    return r;
}

/* Fresh batches from the allocator, then a selection into them: a failed selection leaves them
 * empty. They may keep storage grown for the next frame (they own it), so they are destroyed
 * either way. */
static xyl_result tess_select(const xyl_allocator *a)
{
    xyl_tess_batches *b = UNTOUCHED;
    xyl_diag diag = {0};
    xyl_result r = xyl_tess_batches_create(a, &b, &diag);
    if (r != XYL_OK) {
        assert_ptr_equal(b, UNTOUCHED);
        return r;
    }
    xyl_tess_view v = {0};
    v.eye[2] = 4.0f;
    r = xyl_tess_select(in.patches, in.patterns, &v, b, &diag);
    if (r != XYL_OK) {
        assert_int_equal(b->instance_count + b->cmd_count, 0);
        assert_true(b->triangles == 0 && b->vertices == 0);
    }
    xyl_tess_batches_destroy(b);
    return r;
}

static xyl_result tess_refine(const xyl_allocator *a)
{
    xyl_mesh *m = UNTOUCHED;
    xyl_diag diag = {0};
    xyl_result r = xyl_tess_refine(in.patches, in.patterns, in.batches, NULL, a, &m, &diag);
    return mesh_done(r, m);
}

/* ---- foliage -------------------------------------------------------------------------------- */

/* Two leaves, one a quad and one a fan of two triangles. */
static xyl_result leaves_from_obj(const xyl_allocator *a)
{
    static const char text[] = "v 0 0 0\nv 1 0 0\nv 1 2 0\nv 0 2 0\nf 1 2 3 4\n"
                               "v 5 0 0\nv 6 1 0\nv 5 3 0\nv 4 1 0\nf 5 6 7\nf 5 7 8\n";
    xyl_leaf_mesh_desc d = {0};
    d.alloc = *a;
    xyl_leaf leaves[2], before[2];
    memset(leaves, 0x5a, sizeof leaves);
    memcpy(before, leaves, sizeof leaves);
    size_t n = 7;
    xyl_diag diag = {0};
    xyl_result r = xyl_foliage_leaves_from_obj(text, sizeof text - 1, &d, leaves, 2, &n, &diag);
    if (r == XYL_OK) {
        assert_int_equal(n, 2);
    } else {
        assert_int_equal(n, 7);
        assert_memory_equal(leaves, before, sizeof leaves);
    }
    return r;
}

/* Two leaves against one: images, grids and tidy copies all come from the allocator. */
static xyl_result foliage_image_error(const xyl_allocator *a)
{
    xyl_leaf l[3];
    memset(l, 0, sizeof l);
    for (int i = 0; i < 3; ++i) {
        l[i].center = (xyl_vec3){(float)i, 0.5f * (float)i, 0};
        l[i].normal = (xyl_vec3){0, 0, 1};
        l[i].axis = (xyl_vec3){0, 0.4f, 0};
        l[i].side = (xyl_vec3){0.2f, 0, 0};
        l[i].node = -1;
    }
    xyl_foliage_image_desc d = {0};
    d.resolution = 16;
    d.alloc = *a;
    xyl_foliage_image_error e, before;
    memset(&e, 0x5A, sizeof e);
    before = e;
    xyl_diag diag = {0};
    xyl_result r = xyl_foliage_image_error_of(l, 2, l + 1, 2, &d, &e, &diag);
    if (r != XYL_OK) assert_memory_equal(&e, &before, sizeof e);
    return r;
}

/* Two leaves against three triangles. */
static xyl_result foliage_image_error_triangles(const xyl_allocator *a)
{
    xyl_leaf l[2];
    memset(l, 0, sizeof l);
    for (int i = 0; i < 2; ++i) {
        l[i].center = (xyl_vec3){(float)i, 0.5f * (float)i, 0};
        l[i].normal = (xyl_vec3){0, 0, 1};
        l[i].axis = (xyl_vec3){0, 0.4f, 0};
        l[i].side = (xyl_vec3){0.2f, 0, 0};
        l[i].node = -1;
    }
    const float pos[12] = {0, 0, 0, 1, 0, 0, 0, 1, 0, 1, 1, 0.5f};
    const uint32_t idx[9] = {0, 1, 2, 1, 3, 2, 0, 3, 2};
    xyl_foliage_image_desc d = {0};
    d.resolution = 16;
    d.alloc = *a;
    xyl_foliage_image_error e, before;
    memset(&e, 0x5A, sizeof e);
    before = e;
    xyl_diag diag = {0};
    xyl_result r = xyl_foliage_image_error_triangles(l, 2, pos, 4, idx, 3, &d, &e, &diag);
    if (r != XYL_OK) assert_memory_equal(&e, &before, sizeof e);
    return r;
}

/* ---- the suite ------------------------------------------------------------------------------ */

static const walk_case cases[] = {
    {"xyl_grammar_parse", grammar_parse, false, true},
    {"xyl_lsystem_derive", lsystem_derive, false, true},
    {"xyl_lsystem_interpret", interpret_pipe, false, true},
    {"xyl_lsystem_interpret (Murray angles)", interpret_murray, false, true},
    {"xyl_skeleton_create", skeleton_create, false, true},
    {"xyl_skeleton_read_text", skeleton_read_text, false, true},
    {"xyl_skeleton_read_file", skeleton_read_file, false, true},
    {"xyl_skeleton_write_file (skel)", skeleton_write_skel, false, true},
    {"xyl_skeleton_write_file (obj)", skeleton_write_obj, false, true},
    {"xyl_skeleton_write_text", skeleton_write_text, false, false},
    {"xyl_stems_build (unchecked)", stems_unchecked, false, true},
    {"xyl_stems_build (checked, rebuilt)", stems_checked, false, true},
#if defined(XYL_HAVE_OPENSUBDIV)
    {"xyl_stems_build (Catmull-Clark)", stems_catmark, true, true},
#endif
    {"xyl_skeleton_prune", skeleton_prune, false, true},
    {"xyl_stems_lods_build", stems_lods, false, true},
    {"xyl_stems_lods_write_glb_memory", stems_lods_glb_memory, false, true},
    {"xyl_stems_lods_write_glb_file", stems_lods_glb_file, false, true},
    {"xyl_mesh_create", mesh_create, false, true},
    {"xyl_mesh_check", mesh_check, false, true},
    {"xyl_mesh_self_intersections", mesh_self_intersections, false, true},
    {"xyl_mesh_split_seams", mesh_split_seams, false, true},
#if defined(XYL_HAVE_OPENSUBDIV)
    {"xyl_mesh_subdivide (Catmull-Clark)", mesh_subdivide_catmark, true, true},
    {"xyl_mesh_subdivide (Loop)", mesh_subdivide_loop, true, true},
#endif
    {"xyl_mesh_write_memory (obj)", write_memory_obj, false, true},
    {"xyl_mesh_write_memory (glb)", write_memory_glb, false, true},
    {"xyl_mesh_write_file (obj)", write_file_obj, false, true},
    {"xyl_mesh_write_file (glb)", write_file_glb, false, true},
    {"xyl_foliage_write_glb_memory (stems)", foliage_glb_memory_stems, false, true},
    {"xyl_foliage_write_glb_memory (leaves)", foliage_glb_memory_leaves, false, false},
    {"xyl_foliage_write_glb_file", foliage_glb_file, false, true},
    {"xyl_tess_patches_create", tess_patches, false, true},
    {"xyl_tess_patterns_create", tess_patterns, false, true},
    {"xyl_tess_select", tess_select, false, true},
    {"xyl_tess_refine", tess_refine, false, true},
    {"xyl_foliage_leaves_from_obj", leaves_from_obj, false, true},
    {"xyl_foliage_image_error_of", foliage_image_error, false, true},
    {"xyl_foliage_image_error_triangles", foliage_image_error_triangles, false, true},
};

static void every_call_survives_each_allocation_failure_and_uses_only_its_allocator(void **state)
{
    (void)state;
    size_t total = 0;
    for (size_t i = 0; i < sizeof cases / sizeof cases[0]; ++i) {
        size_t foreign = 0, points = walk(&cases[i], &foreign);
        print_message("%-40s %4zu allocations, failed in turn", cases[i].name, points);
        if (foreign) print_message(" (and %zu blocks of OpenSubdiv's own)", foreign);
        print_message("\n");
        total += points;
    }
    print_message("%zu calls, %zu failing runs\n", sizeof cases / sizeof cases[0], total);
}

/* The watch must see what it is there to catch: the default allocator behind a call's back,
 * small blocks (malloc) and big ones (mapped, where the build maps them), and the C library's
 * own use of malloc (stdio's FILE). */
static void the_watch_sees_the_default_allocator_and_the_c_library(void **state)
{
    (void)state;
    if (!WATCHES_MALLOC) skip();
    strays s;
    watch_begin();
    xyl__free(NULL, xyl__alloc(NULL, 100));
    watch_end(&s);
    assert_int_equal(s.calls, 1);
    assert_int_equal(s.live, 0);
    watch_begin();
    FILE *f = fopen("/dev/null", "rb");
    assert_non_null(f);
    fclose(f);
    watch_end(&s);
    assert_true(s.calls >= 1);
    assert_int_equal(s.live, 0);
#if defined(XYL__LARGE_BLOCKS)
    watch_begin();
    xyl__free(NULL, xyl__alloc(NULL, 4 * XYL__LARGE_BLOCK));
    assert_int_equal(watch_end(&s), 1);
    assert_int_equal(s.calls, 0);
#endif
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(the_watch_sees_the_default_allocator_and_the_c_library),
        cmocka_unit_test(every_call_survives_each_allocation_failure_and_uses_only_its_allocator),
    };
    return cmocka_run_group_tests(tests, setup, teardown);
}
