/* A glTF 2.0 binary (.glb) assembled by hand, for the writers of mesh/ (stems) and foliage/
 * (leaves, with or without stems): a byte sink that counts or stores, and a document of buffer
 * views and accessors around JSON the writer supplies. Not installed.
 *
 * A writer fills a xyl__glb (views with the functions that emit their bytes, accessors, a body
 * function for its own JSON), sizes it with xyl__glb_finish, then emits it into exactly that many
 * bytes. Nothing depends on the C locale or the host's byte order: integers are printed by hand,
 * floats through float_text.h, binary numbers are stored little-endian, as glTF requires. */
#ifndef XYL_GLB_WRITE_H
#define XYL_GLB_WRITE_H

#include "xyl_internal.h"
#include "xylem/xyl_mesh.h"

/* OpenGL enums that glTF uses for component types, buffer targets and primitive modes. */
#define XYL__GL_UNSIGNED_INT 5125
#define XYL__GL_FLOAT 5126
#define XYL__GL_ARRAY_BUFFER 34962
#define XYL__GL_ELEMENT_ARRAY_BUFFER 34963
#define XYL__GL_TRIANGLES 4

/* ---- byte sink ------------------------------------------------------------------------------ */

/* Counts bytes, and also stores them when buf is set: sized by an earlier counting pass, or,
 * with cap set, grown as it goes (from alloc; overflow on failure). */
typedef struct xyl__sink {
    unsigned char *buf;
    size_t len;
    bool overflow; /* the output would not fit in a size_t (with room for a NUL), or memory
                      ran out */
    size_t cap;    /* 0: buf has room for everything */
    const xyl_allocator *alloc;
} xyl__sink;

void xyl__put(xyl__sink *s, const void *bytes, size_t n);
void xyl__put_str(xyl__sink *s, const char *text);
void xyl__put_uint(xyl__sink *s, uint64_t v);
/* The shortest text that reads back as the same float: valid JSON for finite values. */
void xyl__put_float(xyl__sink *s, float v);
/* The shortest text that reads back as the same double. */
void xyl__put_double(xyl__sink *s, double v);
/* A node's ",\"translation\":[x,y,z]" for a mesh's origin, nothing for an origin of 0. */
void xyl__put_json_translation(xyl__sink *s, const double origin[3]);
void xyl__put_u32le(xyl__sink *s, uint32_t v);
void xyl__put_f32le(xyl__sink *s, float v);
void xyl__put_padding(xyl__sink *s, size_t n, char byte);
/* key (with its quotes, colon and any leading comma) then [x,y,z]. */
void xyl__put_json_vec3(xyl__sink *s, const char *key, xyl_vec3 v);
/* A NORMAL for glTF: a normal whose squared length is within 1e-5 of 1 passes bit for bit,
 * others are renormalised (a zero one becomes +Y), because the glTF-Validator rejects NORMAL
 * elements that are not unit (it allows about 5e-4 in the length; this keeps far inside it). */
xyl_vec3 xyl__glb_unit_normal(xyl_vec3 n);

/* ---- the document --------------------------------------------------------------------------- */

/* Five views a mesh: room for the stem LOD chain's 12 meshes (XYL_STEMS_LOD_MAX). */
#define XYL__GLB_MAX_VIEWS 64

typedef void (*xyl__glb_emit_fn)(const void *ctx, xyl__sink *s);

/* A buffer view: bytes of the BIN chunk that emit writes (exactly `bytes`), placed at the next
 * multiple of 4. */
typedef struct xyl__glb_view {
    uint64_t bytes;
    int target;          /* bufferView target; 0 for none (an image) */
    xyl__glb_emit_fn emit;
    const void *ctx;
    uint64_t offset;     /* set by xyl__glb_layout */
} xyl__glb_view;

typedef struct xyl__glb_accessor {
    uint32_t view;
    int component;       /* componentType */
    const char *type;    /* "SCALAR", "VEC2", "VEC3" */
    uint64_t count;
    bool bounds;         /* write min and max (POSITION needs them) */
    xyl_vec3 min, max;
} xyl__glb_accessor;

/* The JSON is {"asset":{...},"scene":0, BODY ,"accessors":[..],"bufferViews":[..],
 * "buffers":[..]} (the last three only with a view): body writes the scenes, nodes, meshes and
 * whatever else, without a leading or trailing comma. body must write the same bytes each time
 * it is called. */
typedef struct xyl__glb {
    xyl__glb_view views[XYL__GLB_MAX_VIEWS];
    uint32_t view_count;
    xyl__glb_accessor accessors[XYL__GLB_MAX_VIEWS];
    uint32_t accessor_count;
    xyl__glb_emit_fn body;
    const void *body_ctx;
    uint64_t bin_len;  /* xyl__glb_layout: 0 when there is no view */
    uint64_t json_len; /* xyl__glb_finish: before padding */
    uint64_t total;    /* xyl__glb_finish: the file's size */
} xyl__glb;

/* Appends a view (the caller keeps within XYL__GLB_MAX_VIEWS); returns its index. */
uint32_t xyl__glb_add_view(xyl__glb *g, uint64_t bytes, int target, xyl__glb_emit_fn emit,
                           const void *ctx);
/* Appends an accessor of a view's whole bytes; returns its index. */
uint32_t xyl__glb_add_accessor(xyl__glb *g, uint32_t view, int component, const char *type,
                               uint64_t count);

/* Places the views in the BIN chunk (offsets, bin_len) and returns the file's size without the
 * JSON: a lower bound that refuses an oversized document before its arrays are read. Each view
 * must be under 2^60 bytes. */
uint64_t xyl__glb_layout(xyl__glb *g);
/* Every length field of a GLB is a uint32: XYL_ERR_LIMIT_EXCEEDED for a file of `bytes`. */
xyl_result xyl__glb_too_large(uint64_t bytes, xyl_diag *diag);
/* Lays out, counts the JSON and sets total; XYL_ERR_LIMIT_EXCEEDED when it exceeds 4 GiB. */
xyl_result xyl__glb_finish(xyl__glb *g, xyl_diag *diag);
/* Writes the finished document: exactly g->total bytes. */
void xyl__glb_emit(const xyl__glb *g, xyl__sink *s);

/* A finished document into a caller's buffer, count-then-fill: *size = g->total; with out
 * set and capacity < total, XYL_ERR_INVALID_ARGUMENT and out untouched. */
xyl_result xyl__glb_write_memory(const xyl__glb *g, void *out, size_t capacity, size_t *size,
                                 xyl_diag *diag);
/* A finished document to path, atomically (xyl__write_file_atomic), its bytes from alloc. */
xyl_result xyl__glb_write_file(const xyl__glb *g, const char *path, const xyl_allocator *alloc,
                               xyl_diag *diag);

/* ---- a mesh as a glTF mesh (mesh_io.c) ------------------------------------------------------ */

/* A mesh's part of a document: its seams split where it has wraps, five views (POSITION,
 * NORMAL, TEXCOORD_0, _BRANCH_ID, indices) and their accessors. */
typedef struct xyl__glb_mesh {
    const xyl_mesh *mesh; /* the one written: the split mesh or the caller's */
    xyl_mesh *split;      /* owned; NULL where the mesh has no seams */
    uint32_t first_accessor;
    bool empty;           /* no vertices: no views, no glTF mesh */
} xyl__glb_mesh;

/* Checks m for a GLB (a valid view, branch ids that floats hold, at least one face when it has
 * vertices, a size within 4 GiB) and adds its views and accessors to g. On failure g and *out
 * hold nothing new. Errors: XYL_ERR_INVALID_ARGUMENT, XYL_ERR_NON_FINITE, XYL_ERR_LIMIT_EXCEEDED,
 * XYL_ERR_OUT_OF_MEMORY (the split, from alloc). */
xyl_result xyl__glb_mesh_add(const xyl_mesh *m, const xyl_allocator *alloc, xyl__glb *g,
                             xyl__glb_mesh *out, xyl_diag *diag);
/* {"name":"stems","primitives":[...]}: the glTF mesh of a non-empty part. */
void xyl__glb_mesh_json(const xyl__glb_mesh *p, xyl__sink *s);
/* The same without its closing brace, for a writer that adds members (the LOD chain's
 * "extras"). */
void xyl__glb_mesh_json_open(const xyl__glb_mesh *p, xyl__sink *s);
void xyl__glb_mesh_free(xyl__glb_mesh *p);

#endif
