/* OpenSubdiv shim: one uniform level of Catmull-Clark or Loop refinement through Far
 * (docs/subdivision.md). One of the library's two C++ files: every entry point is extern "C" and
 * catches every exception, so none reaches C. */
#include "subdivide.h"

#include <cmath>
#include <cstring>
#include <memory>
#include <new>
#include <stdexcept>
#include <type_traits>
#include <utility>

#include <opensubdiv/far/primvarRefiner.h>
#include <opensubdiv/far/topologyDescriptor.h>
#include <opensubdiv/far/topologyRefinerFactory.h>

namespace {

namespace Far = OpenSubdiv::Far;
namespace Sdc = OpenSubdiv::Sdc;

/* An array of trivial T from the caller's allocator, zero-filled, freed unless released. */
template <class T> class Buffer {
    static_assert(std::is_trivial<T>::value, "Buffer holds plain data only");

public:
    Buffer(const xyl_allocator *alloc, size_t count)
        : alloc_(alloc), p_(static_cast<T *>(xyl__calloc(alloc, count ? count : 1, sizeof(T))))
    {
    }
    /* Without an array: get() is NULL until allocate(). */
    explicit Buffer(const xyl_allocator *alloc) : alloc_(alloc), p_(nullptr) {}
    bool allocate(size_t count)
    {
        xyl__free(alloc_, p_);
        p_ = static_cast<T *>(xyl__calloc(alloc_, count ? count : 1, sizeof(T)));
        return p_ != nullptr;
    }
    /* An array the caller writes in full before reading it: not zero-filled. */
    bool allocate_unset(size_t count)
    {
        xyl__free(alloc_, p_);
        p_ = static_cast<T *>(xyl__alloc_array(alloc_, count ? count : 1, sizeof(T)));
        return p_ != nullptr;
    }
    ~Buffer() { xyl__free(alloc_, p_); }
    Buffer(const Buffer &) = delete;
    Buffer &operator=(const Buffer &) = delete;

    T *get() const { return p_; }
    void swap(Buffer &other)
    {
        std::swap(alloc_, other.alloc_);
        std::swap(p_, other.p_);
    }
    T *release()
    {
        T *p = p_;
        p_ = nullptr;
        return p;
    }

private:
    const xyl_allocator *alloc_;
    T *p_;
};

/* Primvars for Far::PrimvarRefinerReal<double>: sums in double. */
struct Point3 {
    double x, y, z;
    void Clear() { x = y = z = 0.0; }
    void AddWithWeight(const Point3 &s, double w)
    {
        x += w * s.x;
        y += w * s.y;
        z += w * s.z;
    }
};

struct Point2 {
    double u, v;
    void Clear() { u = v = 0.0; }
    void AddWithWeight(const Point2 &s, double w)
    {
        u += w * s.u;
        v += w * s.v;
    }
};

using Refiner = Far::TopologyRefiner;
using Factory = Far::TopologyRefinerFactory<Far::TopologyDescriptor>;
using DoubleRefiner = Far::PrimvarRefinerReal<double>;

constexpr uint64_t kIntMax = 0x7fffffff; /* Far::Index is int */

size_t face_count(const xyl__mesh_arrays *a)
{
    return a->quad_count + a->triangle_count;
}

/* Face f's vertex indices (quads first, then triangles) and their number. */
const uint32_t *face_vertices(const xyl__mesh_arrays *a, size_t f, int *n)
{
    if (f < a->quad_count) {
        *n = 4;
        return a->quads + 4 * f;
    }
    *n = 3;
    return a->triangles + 3 * (f - a->quad_count);
}

xyl_result validate_input(const xyl__mesh_arrays *a, xyl_diag *diag)
{
    const xyl_mesh view = XYL__MESH_VIEW_OF(a);
    return xyl__mesh_validate(&view, XYL__MESH_FACES | XYL__MESH_UV_WRAPS, diag);
}

struct Limits {
    uint64_t vertices, faces;
};

Limits effective_limits(const xyl_mesh_limits *l)
{
    Limits r = {XYL__MESH_DEFAULT_MAX_VERTICES, XYL__MESH_DEFAULT_MAX_FACES};
    if (l && l->max_vertices) r.vertices = l->max_vertices;
    if (l && l->max_faces) r.faces = l->max_faces;
    return r;
}

xyl_result check_limits(uint64_t vertices, uint64_t faces, const Limits &lim, xyl_diag *diag)
{
    if (vertices > lim.vertices || faces > lim.faces)
        return xyl__fail(diag, XYL_ERR_LIMIT_EXCEEDED, 0, 0, -1,
                         "the refined mesh would have %llu vertices and %llu faces; the limits "
                         "are %llu and %llu",
                         static_cast<unsigned long long>(vertices),
                         static_cast<unsigned long long>(faces),
                         static_cast<unsigned long long>(lim.vertices),
                         static_cast<unsigned long long>(lim.faces));
    return XYL_OK;
}

/* Copies src (count elements of T) into a new array, or zeros when src is NULL. */
template <class T> T *copy_or_zero(const xyl_allocator *alloc, const T *src, size_t count)
{
    Buffer<T> b(alloc, count);
    if (b.get() && src && count) std::memcpy(b.get(), src, count * sizeof(T));
    return b.release();
}

/* XYL_SUBDIVIDE_NONE, and any scheme on a mesh without faces (nothing to refine). */
xyl_result copy_mesh(const xyl__mesh_arrays *in, bool keep_normals, const xyl_allocator *alloc,
                     xyl__mesh_arrays *out, xyl_diag *diag)
{
    const size_t nv = in->vertex_count, nf = face_count(in);
    xyl__mesh_arrays a;
    std::memset(&a, 0, sizeof a);
    a.vertex_count = nv;
    a.quad_count = in->quad_count;
    a.triangle_count = in->triangle_count;
    a.positions = copy_or_zero(alloc, in->positions, nv);
    if (keep_normals && in->normals) a.normals = copy_or_zero(alloc, in->normals, nv);
    a.uvs = copy_or_zero(alloc, in->uvs, 2 * nv);
    a.branch_ids = copy_or_zero(alloc, in->branch_ids, nv);
    a.quads = copy_or_zero(alloc, in->quads, 4 * in->quad_count);
    a.triangles = copy_or_zero(alloc, in->triangles, 3 * in->triangle_count);
    a.face_branches = copy_or_zero(alloc, in->face_branches, nf);
    a.uv_wraps = copy_or_zero(alloc, in->uv_wraps, nf);
    if (!a.positions || (keep_normals && in->normals && !a.normals) || !a.uvs || !a.branch_ids ||
        !a.quads || !a.triangles || !a.face_branches || !a.uv_wraps) {
        xyl__mesh_arrays_free(&a, alloc);
        return xyl__fail(diag, XYL_ERR_OUT_OF_MEMORY, 0, 0, -1, "out of memory copying the mesh");
    }
    *out = a;
    return XYL_OK;
}

/* The control mesh as Far wants it: per-face vertex counts and int indices, quads split in two
 * triangles for Loop, and the branch of each Far face. */
struct Control {
    Buffer<int> counts;
    Buffer<int> indices;
    Buffer<uint32_t> branches;
    Buffer<uint8_t> wraps; /* the uv wrap bits of each Far face's corners */
    int faces;

    Control(const xyl_allocator *alloc, size_t faces_, size_t corners)
        : counts(alloc, faces_), indices(alloc, corners), branches(alloc, faces_),
          wraps(alloc, faces_), faces(static_cast<int>(faces_))
    {
    }
    bool ok() const { return counts.get() && indices.get() && branches.get() && wraps.get(); }
};

/* Bit `from` of bits as bit `to`. */
uint8_t wrap_bit(uint8_t bits, int from, int to)
{
    return static_cast<uint8_t>((bits >> from & 1u) << to);
}

void fill_control(const xyl__mesh_arrays *in, bool loop, Control *c)
{
    int *count = c->counts.get(), *idx = c->indices.get();
    uint32_t *branch = c->branches.get();
    uint8_t *wrap = c->wraps.get();
    for (size_t f = 0; f < face_count(in); ++f) {
        int n = 0;
        const uint32_t *fv = face_vertices(in, f, &n);
        uint32_t b = in->face_branches ? in->face_branches[f] : 0;
        uint8_t w = in->uv_wraps ? in->uv_wraps[f] : 0;
        if (loop && n == 4) {
            const uint32_t split[6] = {fv[0], fv[1], fv[2], fv[0], fv[2], fv[3]};
            for (uint32_t s : split) *idx++ = static_cast<int>(s);
            *count++ = 3;
            *count++ = 3;
            *branch++ = b;
            *branch++ = b;
            *wrap++ = static_cast<uint8_t>(w & 7u);
            *wrap++ = static_cast<uint8_t>(wrap_bit(w, 0, 0) | wrap_bit(w, 2, 1) |
                                           wrap_bit(w, 3, 2));
            continue;
        }
        for (int k = 0; k < n; ++k) *idx++ = static_cast<int>(fv[k]);
        *count++ = n;
        *branch++ = b;
        *wrap++ = w;
    }
}

/* The infinitely sharp edges asked for (xyl__creases), pairs of input vertex indices. */
struct Creases {
    const uint32_t *pairs;
    size_t count;
};

/* Every crease joins two distinct vertices in range; else XYL_ERR_INVALID_ARGUMENT naming it. */
xyl_result check_crease_ends(const xyl__mesh_arrays *in, const Creases &c, xyl_diag *diag)
{
    const size_t nv = in->vertex_count;
    for (size_t i = 0; i < c.count; ++i) {
        const uint32_t a = c.pairs[2 * i], b = c.pairs[2 * i + 1];
        if (a >= nv || b >= nv || a == b)
            return xyl__fail(diag, XYL_ERR_INVALID_ARGUMENT, 0, 0, static_cast<int64_t>(i),
                             "crease %zu joins vertices %u and %u, not two distinct vertices "
                             "of the %zu", i, a, b, nv);
    }
    return XYL_OK;
}

xyl_result not_an_edge(const Creases &c, size_t i, xyl_diag *diag)
{
    return xyl__fail(diag, XYL_ERR_INVALID_ARGUMENT, 0, 0, static_cast<int64_t>(i),
                     "crease %zu joins vertices %u and %u, which no face has as a side", i,
                     c.pairs[2 * i], c.pairs[2 * i + 1]);
}

/* Every crease (its ends checked) is a side of a face of the control mesh as refined (Loop's
 * quads split in two); else XYL_ERR_INVALID_ARGUMENT naming it. Each vertex's outgoing sides
 * are gathered once, so the check costs one pass over the faces. The direct path finds the
 * creases in its own half-edges instead (mark_creases). */
xyl_result check_creases(const Control &control, int vertices, const Creases &c,
                         const xyl_allocator *alloc, xyl_diag *diag)
{
    if (c.count == 0) return XYL_OK;
    const size_t nv = size_t(vertices);
    const int *count = control.counts.get(), *idx = control.indices.get();
    size_t corners = 0;
    for (int f = 0; f < control.faces; ++f) corners += size_t(count[f]);
    Buffer<size_t> start(alloc, nv + 1);
    Buffer<uint32_t> head(alloc);
    if (!start.get() || !head.allocate_unset(corners))
        return xyl__fail(diag, XYL_ERR_OUT_OF_MEMORY, 0, 0, -1, "out of memory for the creases");
    size_t *st = start.get();
    for (size_t i = 0; i < corners; ++i) ++st[idx[i] + 1];
    for (size_t v = 0; v < nv; ++v) st[v + 1] += st[v];
    for (int f = 0, s = 0; f < control.faces; s += count[f++]) /* st[v] ends at v's end ... */
        for (int k = 0; k < count[f]; ++k)
            head.get()[st[idx[s + k]]++] = uint32_t(idx[s + (k + 1 < count[f] ? k + 1 : 0)]);
    for (size_t v = nv; v > 0; --v) st[v] = st[v - 1]; /* ... and shifts back to its start */
    st[0] = 0;
    auto side = [&](uint32_t from, uint32_t to) {
        for (size_t i = st[from]; i < st[from + 1]; ++i)
            if (head.get()[i] == to) return true;
        return false;
    };
    for (size_t i = 0; i < c.count; ++i) {
        const uint32_t a = c.pairs[2 * i], b = c.pairs[2 * i + 1];
        if (!side(a, b) && !side(b, a)) return not_an_edge(c, i, diag);
    }
    return XYL_OK;
}

std::unique_ptr<Refiner> create_refiner(Sdc::SchemeType type, int vertices, const Control &c,
                                        const Creases &creases, const xyl_allocator *alloc)
{
    Far::TopologyDescriptor desc;
    desc.numVertices = vertices;
    desc.numFaces = c.faces;
    desc.numVertsPerFace = c.counts.get();
    desc.vertIndicesPerFace = c.indices.get();
    /* checked by check_crease_ends: indices in range, so they fit Far's int */
    Buffer<int> pairs(alloc);
    Buffer<float> weights(alloc);
    if (creases.count) {
        if (!pairs.allocate_unset(2 * creases.count) || !weights.allocate_unset(creases.count))
            throw std::bad_alloc();
        for (size_t i = 0; i < creases.count; ++i) {
            pairs.get()[2 * i] = static_cast<int>(creases.pairs[2 * i]);
            pairs.get()[2 * i + 1] = static_cast<int>(creases.pairs[2 * i + 1]);
            weights.get()[i] = Sdc::Crease::SHARPNESS_INFINITE;
        }
        desc.numCreases = static_cast<int>(creases.count);
        desc.creaseVertexIndexPairs = pairs.get();
        desc.creaseWeights = weights.get();
    }
    Sdc::Options sdc;
    /* Boundaries (none on a closed stem mesh) stay put: sharp edges and corners. */
    sdc.SetVtxBoundaryInterpolation(Sdc::Options::VTX_BOUNDARY_EDGE_AND_CORNER);
    return std::unique_ptr<Refiner>(Factory::Create(desc, Factory::Options(type, sdc)));
}

/* The branch of the vertex an edge gives birth to: the branch of its faces when they agree,
 * else (a seam between branches) its end vertices' branch when they agree, else the smallest
 * of its faces' branches. faces: the edge's faces (count of them), ends: its end vertices. */
uint32_t edge_branch(const int *faces, int count, const int ends[2], const uint32_t *vertex_branch,
                     const uint32_t *face_branch)
{
    bool agree = true;
    uint32_t lowest = UINT32_MAX;
    for (int i = 0; i < count; ++i) {
        uint32_t b = face_branch[faces[i]];
        agree = agree && b == face_branch[faces[0]];
        lowest = b < lowest ? b : lowest;
    }
    if (count > 0 && agree) return lowest;
    uint32_t b0 = vertex_branch ? vertex_branch[ends[0]] : 0;
    uint32_t b1 = vertex_branch ? vertex_branch[ends[1]] : 0;
    if (b0 == b1 || count == 0) return b0 < b1 ? b0 : b1;
    return lowest;
}

uint32_t edge_branch(const Far::TopologyLevel &base, Far::Index e, const uint32_t *vertex_branch,
                     const uint32_t *face_branch)
{
    Far::ConstIndexArray faces = base.GetEdgeFaces(e), ends = base.GetEdgeVertices(e);
    const int end[2] = {ends[0], ends[1]};
    return edge_branch(faces.begin(), faces.size(), end, vertex_branch, face_branch);
}

void assign_vertex_branches(const Refiner &r, const xyl__mesh_arrays *in,
                            const uint32_t *face_branch, bool face_points, uint32_t *out)
{
    const Far::TopologyLevel &base = r.GetLevel(0);
    for (int v = 0; v < base.GetNumVertices(); ++v)
        out[base.GetVertexChildVertex(v)] = in->branch_ids ? in->branch_ids[v] : 0;
    for (int e = 0; e < base.GetNumEdges(); ++e)
        out[base.GetEdgeChildVertex(e)] = edge_branch(base, e, in->branch_ids, face_branch);
    /* Loop has no face points (and Far keeps no face-child table to ask). */
    if (!face_points) return;
    for (int f = 0; f < base.GetNumFaces(); ++f) out[base.GetFaceChildVertex(f)] = face_branch[f];
}

/* The refined arrays, allocated from the caller's allocator before any is filled. */
struct Refined {
    Buffer<xyl_vec3> positions;
    Buffer<xyl_vec3> normals; /* limit normals; empty (NULL) for control points */
    Buffer<float> uvs;
    Buffer<uint32_t> branch_ids;
    Buffer<uint32_t> faces;
    Buffer<uint32_t> face_branches;
    Buffer<uint8_t> wraps;

    Refined(const xyl_allocator *alloc, size_t vertices, size_t faces_, int corners, bool limit)
        : positions(alloc, vertices), normals(alloc), uvs(alloc, 2 * vertices),
          branch_ids(alloc, vertices), faces(alloc, faces_ * static_cast<size_t>(corners)),
          face_branches(alloc, faces_), wraps(alloc, faces_)
    {
        if (limit) normals.allocate(vertices);
    }
    bool ok(bool limit) const
    {
        return positions.get() && (!limit || normals.get()) && uvs.get() && branch_ids.get() &&
               faces.get() && face_branches.get() && wraps.get();
    }
};

Point3 sub(const Point3 &a, const Point3 &b)
{
    return Point3{a.x - b.x, a.y - b.y, a.z - b.z};
}

Point3 cross(const Point3 &a, const Point3 &b)
{
    return Point3{a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x};
}

double dot(const Point3 &a, const Point3 &b)
{
    return a.x * b.x + a.y * b.y + a.z * b.z;
}

/* The area-weighted normal of a level-1 face with corners fv (twice the area for triangles, the
 * diagonals' cross product for quads). */
template <class Index> Point3 face_normal(const Index *fv, int corners, const Point3 *p)
{
    return corners == 4 ? cross(sub(p[fv[2]], p[fv[0]]), sub(p[fv[3]], p[fv[1]]))
                        : cross(sub(p[fv[1]], p[fv[0]]), sub(p[fv[2]], p[fv[0]]));
}

/* Sum of the area-weighted normals of a level-1 vertex's faces: the orientation reference for
 * its limit normal, and the normal where the limit tangents are degenerate. */
Point3 face_normal_sum(const Far::TopologyLevel &fine, Far::Index v, const Point3 *p)
{
    Point3 sum = {0.0, 0.0, 0.0};
    Far::ConstIndexArray faces = fine.GetVertexFaces(v);
    for (int i = 0; i < faces.size(); ++i) {
        Far::ConstIndexArray fv = fine.GetFaceVertices(faces[i]);
        sum.AddWithWeight(face_normal(fv.begin(), fv.size(), p), 1.0);
    }
    return sum;
}

xyl_vec3 unit_or(const Point3 &n, const Point3 &fallback)
{
    double l = std::sqrt(dot(n, n));
    if (!(l > 0.0) || !std::isfinite(l)) {
        double lf = std::sqrt(dot(fallback, fallback));
        if (!(lf > 0.0) || !std::isfinite(lf)) return xyl_vec3{0.0f, 1.0f, 0.0f};
        return xyl_vec3{float(fallback.x / lf), float(fallback.y / lf), float(fallback.z / lf)};
    }
    return xyl_vec3{float(n.x / l), float(n.y / l), float(n.z / l)};
}

/* The cross product of two limit tangents, or zero where they are (numerically) parallel:
 * |n| <= 1e-9 |t1| |t2|. Far from that bound (|n|^2 >= 1e-17 |t1|^2 |t2|^2 with both sides
 * normal numbers, a margin of sqrt(10) that no rounding closes) the square roots are skipped:
 * the answer is the same. */
inline Point3 tangent_normal(const Point3 &t1, const Point3 &t2)
{
    Point3 n = cross(t1, t2);
    const double nn = dot(n, n), tt = dot(t1, t1) * dot(t2, t2);
    if (tt > 1e-280 && tt < 1e280 && nn >= 1e-17 * tt) return n; /* else the exact test */
    double scale = std::sqrt(tt);
    if (!(std::sqrt(nn) > 1e-9 * scale)) n = Point3{0.0, 0.0, 0.0};
    return n;
}

/* The unit limit normal: n turned to agree with the faces' winding (ref), or the faces' normal
 * where n is zero. */
xyl_vec3 oriented_normal(Point3 n, const Point3 &ref)
{
    if (dot(n, ref) < 0.0) n = Point3{-n.x, -n.y, -n.z};
    return unit_or(n, ref);
}

/* Moves the level-1 points pd to their limit positions and writes the limit normals: the cross
 * product of the limit tangents, turned to agree with the faces' winding. Where the tangents
 * are (numerically) parallel, the faces' normal. */
bool project_to_limit(const Refiner &r, const xyl_allocator *alloc, Point3 *pd, xyl_vec3 *normals)
{
    const Far::TopologyLevel &fine = r.GetLevel(1);
    const size_t n1 = static_cast<size_t>(fine.GetNumVertices());
    Buffer<Point3> lim(alloc, n1), du(alloc, n1), dv(alloc, n1);
    if (!lim.get() || !du.get() || !dv.get()) return false;
    const Point3 *src = pd;
    Point3 *lp = lim.get(), *t1 = du.get(), *t2 = dv.get();
    DoubleRefiner(r).Limit(src, lp, t1, t2);
    for (size_t v = 0; v < n1; ++v)
        normals[v] = oriented_normal(tangent_normal(t1[v], t2[v]),
                                     face_normal_sum(fine, static_cast<Far::Index>(v), lp));
    std::memcpy(pd, lp, n1 * sizeof *pd);
    return true;
}

/* What a level-1 vertex is born of: a base vertex, edge or face (the index of which). */
struct Origin {
    enum Kind : uint8_t { VERTEX, EDGE, FACE } kind;
    int index;
};

/* The two levels as the UV pass reads them, from Far's refiner. */
class FarLevels {
public:
    FarLevels(const Refiner &r, bool face_points, const xyl_allocator *alloc)
        : base_(r.GetLevel(0)), fine_(r.GetLevel(1)), face_points_(face_points), origin_(alloc)
    {
    }
    int faces() const { return base_.GetNumFaces(); }
    int face_size(int f) const { return base_.GetFaceVertices(f).size(); }
    int face_vertex(int f, int c) const { return base_.GetFaceVertices(f)[c]; }
    int face_edge(int f, int c) const { return base_.GetFaceEdges(f)[c]; }
    int edge_vertex(int e, int end) const { return base_.GetEdgeVertices(e)[end]; }
    int child_faces(int f) const { return base_.GetFaceChildFaces(f).size(); }
    int child_face(int f, int i) const { return base_.GetFaceChildFaces(f)[i]; }
    int fine_face_size(int cf) const { return fine_.GetFaceVertices(cf).size(); }
    int fine_face_vertex(int cf, int c) const { return fine_.GetFaceVertices(cf)[c]; }
    int fine_vertices() const { return fine_.GetNumVertices(); }
    /* What each level-1 vertex is born of (a table, as Far numbers level 1 its own way). */
    bool prepare()
    {
        if (!origin_.allocate(size_t(fine_.GetNumVertices()))) return false;
        Origin *out = origin_.get();
        for (int v = 0; v < base_.GetNumVertices(); ++v)
            out[base_.GetVertexChildVertex(v)] = Origin{Origin::VERTEX, v};
        for (int e = 0; e < base_.GetNumEdges(); ++e)
            out[base_.GetEdgeChildVertex(e)] = Origin{Origin::EDGE, e};
        if (face_points_)
            for (int f = 0; f < base_.GetNumFaces(); ++f)
                out[base_.GetFaceChildVertex(f)] = Origin{Origin::FACE, f};
        return true;
    }
    Origin origin(int v) const { return origin_.get()[v]; }

private:
    const Far::TopologyLevel &base_, &fine_;
    bool face_points_;
    Buffer<Origin> origin_;
};

/* Base face f in its own UV frame (its corners with their wraps): the UV it gives each kind of
 * level-1 vertex of its child faces, linear as OpenSubdiv's varying rules (a vertex keeps its UV,
 * an edge point averages its ends, a face point the face's corners), and its u span. Faces are
 * quads or triangles. */
struct FaceFrame {
    int n, fv[4], fe[4];
    Point2 corner[4], edge[4], centre;
    double span;

    template <class Levels>
    FaceFrame(const Levels &t, int f, uint8_t wraps, const float *uvs)
        : n(t.face_size(f)), centre{0.0, 0.0}
    {
        double lo = INFINITY, hi = -INFINITY;
        for (int c = 0; c < n; ++c) {
            fv[c] = t.face_vertex(f, c);
            fe[c] = t.face_edge(f, c);
            corner[c] = Point2{uvs ? uvs[2 * fv[c]] : 0.0, uvs ? uvs[2 * fv[c] + 1] : 0.0};
            if (wraps >> c & 1u) corner[c].u += 1.0;
            lo = corner[c].u < lo ? corner[c].u : lo;
            hi = corner[c].u > hi ? corner[c].u : hi;
        }
        span = hi - lo;
        const double w = 1.0 / n;
        for (int c = 0; c < n; ++c) centre.AddWithWeight(corner[c], w);
        for (int e = 0; e < n; ++e) { /* its ends' corners, in corner order */
            const int end0 = t.edge_vertex(fe[e], 0), end1 = t.edge_vertex(fe[e], 1);
            edge[e] = Point2{0.0, 0.0};
            for (int c = 0; c < n; ++c)
                if (fv[c] == end0 || fv[c] == end1) edge[e].AddWithWeight(corner[c], 0.5);
        }
    }

    /* A face whose edge c runs from corner c to the next (every face of the direct path): its
     * edges' UVs without looking up their ends (the same two terms summed as above). */
    struct Consecutive {};
    FaceFrame(Consecutive, const int *vertices, int size, uint8_t wraps, const float *uvs)
        : n(size), centre{0.0, 0.0}
    {
        double lo = INFINITY, hi = -INFINITY;
        for (int c = 0; c < n; ++c) {
            fv[c] = vertices[c];
            fe[c] = -1;
            corner[c] = Point2{uvs ? uvs[2 * fv[c]] : 0.0, uvs ? uvs[2 * fv[c] + 1] : 0.0};
            if (wraps >> c & 1u) corner[c].u += 1.0;
            lo = corner[c].u < lo ? corner[c].u : lo;
            hi = corner[c].u > hi ? corner[c].u : hi;
        }
        span = hi - lo;
        const double w = 1.0 / n;
        for (int c = 0; c < n; ++c) centre.AddWithWeight(corner[c], w);
        for (int c = 0; c < n; ++c) {
            edge[c] = Point2{0.0, 0.0};
            edge[c].AddWithWeight(corner[c], 0.5);
            edge[c].AddWithWeight(corner[c + 1 < n ? c + 1 : 0], 0.5);
        }
    }

    Point2 at(const Origin &o) const
    {
        if (o.kind == Origin::FACE) return centre;
        const int *of = o.kind == Origin::VERTEX ? fv : fe;
        for (int c = 0; c < n; ++c)
            if (of[c] == o.index) return o.kind == Origin::VERTEX ? corner[c] : edge[c];
        return centre; /* not reached: a child face's vertex is born of its parent's parts */
    }
};

/* UVs of level 1 with their seams: each child face's corners take their UV in the parent face's
 * frame, so a face that closed a ring (u from (k - 1)/k to 1) has children that do too. Where
 * the frames of a vertex's faces differ by a whole turn, its UV is the smallest and the others
 * wrap; where they differ otherwise (a cap, whose corners go all around, next to a band; faces
 * at a joint that mix two branches' u), the vertex takes the UV of its narrowest parent face
 * (the smallest of those) and a corner at least half a turn above it wraps, so band faces stay
 * exact. Where no face wraps this is exactly the varying interpolation. Two passes over the
 * base faces (each frame is cheap to make again): the vertices' UVs, then the corners' wraps. */
bool interpolate_uvs(FarLevels &t, const xyl__mesh_arrays *in, const Control &control,
                     const xyl_allocator *alloc, Refined *out)
{
    const size_t n1 = static_cast<size_t>(t.fine_vertices());
    Buffer<Point2> uv(alloc, n1);
    Buffer<double> narrowest(alloc, n1); /* the span of the parent face uv[] came from */
    Buffer<uint8_t> seen(alloc, n1);
    if (!uv.get() || !narrowest.get() || !seen.get() || !t.prepare()) return false;
    const uint8_t *parent_wraps = control.wraps.get();
    for (int f = 0; f < t.faces(); ++f) {
        const FaceFrame frame(t, f, parent_wraps[f], in->uvs);
        for (int i = 0; i < t.child_faces(f); ++i) {
            const int kid = t.child_face(f, i);
            for (int j = 0; j < t.fine_face_size(kid); ++j) {
                const int v = t.fine_face_vertex(kid, j);
                const Point2 c = frame.at(t.origin(v));
                Point2 &own = uv.get()[v];
                double &best = narrowest.get()[v];
                bool take = !seen.get()[v] || frame.span < best ||
                            (frame.span == best && c.u < own.u);
                if (take) own = c, best = frame.span;
                seen.get()[v] = 1;
            }
        }
    }
    for (int f = 0; f < t.faces(); ++f) {
        const FaceFrame frame(t, f, parent_wraps[f], in->uvs);
        for (int i = 0; i < t.child_faces(f); ++i) {
            const int kid = t.child_face(f, i);
            uint8_t bits = 0;
            for (int j = 0; j < t.fine_face_size(kid); ++j) {
                const int v = t.fine_face_vertex(kid, j);
                if (frame.at(t.origin(v)).u - uv.get()[v].u >= 0.5)
                    bits = static_cast<uint8_t>(bits | 1u << j);
            }
            out->wraps.get()[kid] = bits;
        }
    }
    for (size_t v = 0; v < n1; ++v) {
        out->uvs.get()[2 * v] = static_cast<float>(uv.get()[v].u);
        out->uvs.get()[2 * v + 1] = static_cast<float>(uv.get()[v].v);
    }
    return true;
}

/* Positions through the vertex rules in double; with out->normals, they are then moved to the
 * limit surface and the limit normals written. */
bool interpolate_positions(const Refiner &r, const xyl__mesh_arrays *in,
                           const xyl_allocator *alloc, Refined *out)
{
    const size_t n0 = in->vertex_count;
    const size_t n1 = static_cast<size_t>(r.GetLevel(1).GetNumVertices());
    Buffer<Point3> p0(alloc, n0), p1(alloc, n1);
    if (!p0.get() || !p1.get()) return false;
    for (size_t v = 0; v < n0; ++v) {
        const xyl_vec3 p = in->positions[v];
        p0.get()[v] = Point3{p.x, p.y, p.z};
    }
    DoubleRefiner primvar(r);
    const Point3 *ps = p0.get();
    Point3 *pd = p1.get();
    primvar.Interpolate(1, ps, pd);
    if (out->normals.get() && !project_to_limit(r, alloc, pd, out->normals.get())) return false;
    for (size_t v = 0; v < n1; ++v)
        out->positions.get()[v] = xyl_vec3{static_cast<float>(pd[v].x),
                                           static_cast<float>(pd[v].y),
                                           static_cast<float>(pd[v].z)};
    return true;
}

void copy_faces(const Refiner &r, int corners, uint32_t *out)
{
    const Far::TopologyLevel &fine = r.GetLevel(1);
    for (int f = 0; f < fine.GetNumFaces(); ++f) {
        Far::ConstIndexArray fv = fine.GetFaceVertices(f);
        for (int k = 0; k < corners; ++k) *out++ = static_cast<uint32_t>(fv[k]);
    }
}

/* Hands fine's arrays to out: v1 vertices, f1 quads (Catmark) or triangles (Loop). */
xyl_result hand_out(Refined *fine, uint64_t v1, uint64_t f1, bool loop,
                    const xyl_allocator *alloc, xyl__mesh_arrays *out, xyl_diag *diag)
{
    /* The other face array is empty but, as in xyl_mesh_create, not NULL. */
    Buffer<uint32_t> empty(alloc, 0);
    if (!empty.get())
        return xyl__fail(diag, XYL_ERR_OUT_OF_MEMORY, 0, 0, -1, "out of memory for the mesh");
    std::memset(out, 0, sizeof *out);
    out->vertex_count = static_cast<size_t>(v1);
    out->positions = fine->positions.release();
    out->normals = fine->normals.release();
    out->uvs = fine->uvs.release();
    out->branch_ids = fine->branch_ids.release();
    out->face_branches = fine->face_branches.release();
    out->uv_wraps = fine->wraps.release();
    if (loop) {
        out->triangle_count = static_cast<size_t>(f1);
        out->triangles = fine->faces.release();
        out->quads = empty.release();
    } else {
        out->quad_count = static_cast<size_t>(f1);
        out->quads = fine->faces.release();
        out->triangles = empty.release();
    }
    return XYL_OK;
}

/* ---- the direct path ------------------------------------------------------------------------
 * One level built from the base mesh's own structure, for the meshes the stem mesher makes:
 * closed, oriented, every edge in exactly two faces, every vertex in one fan of 3 to
 * kDirectMaxValence faces. It numbers edges, vertices and faces exactly as Far does (edges in
 * the order the faces first meet them, vertex points, then face points, then edge points; the
 * children of a face consecutive, corners rotated as Vtr rotates them), walks each vertex's
 * faces counter-clockwise from the same first face, takes its weights from OpenSubdiv's own
 * Sdc::Scheme masks and sums them in PrimvarRefiner's order, so its output is bit-identical to
 * the Far path's (tests/test_stems.c holds it to that on every preset and hard case). Far's
 * topology tables, which it builds for any refinement, cost ten times what one level needs.
 * Any other mesh takes the Far path. */

constexpr int kDirectMaxValence = 64;

/* Sdc::Scheme's <typename MASK>: Far's own (PrimvarRefiner::Mask) is private. */
class Mask {
public:
    typedef double Weight;
    Mask(Weight *v, Weight *e, Weight *f)
        : v_(v), e_(e), f_(f), nv_(0), ne_(0), nf_(0), centres_(false)
    {
    }
    int GetNumVertexWeights() const { return nv_; }
    int GetNumEdgeWeights() const { return ne_; }
    int GetNumFaceWeights() const { return nf_; }
    void SetNumVertexWeights(int n) { nv_ = n; }
    void SetNumEdgeWeights(int n) { ne_ = n; }
    void SetNumFaceWeights(int n) { nf_ = n; }
    Weight &VertexWeight(int i) { return v_[i]; }
    Weight &EdgeWeight(int i) { return e_[i]; }
    Weight &FaceWeight(int i) { return f_[i]; }
    const Weight &VertexWeight(int i) const { return v_[i]; }
    const Weight &EdgeWeight(int i) const { return e_[i]; }
    const Weight &FaceWeight(int i) const { return f_[i]; }
    bool AreFaceWeightsForFaceCenters() const { return centres_; }
    void SetFaceWeightsForFaceCenters(bool on) { centres_ = on; }

private:
    Weight *v_, *e_, *f_;
    int nv_, ne_, nf_;
    bool centres_;
};

/* The neighbourhoods Sdc asks about: smooth (no sharpness anywhere) and interior. */
struct SmoothFace {
    int n;
    int GetNumVertices() const { return n; }
};

struct SmoothEdge {
    int GetNumFaces() const { return 2; }
    float GetSharpness() const { return 0.0f; }
    void GetChildSharpnesses(const Sdc::Crease &, float s[2]) const { s[0] = s[1] = 0.0f; }
    /* asked for only under TRI_SUB_SMOOTH, which xylem does not set */
    void GetNumVerticesPerFace(int n[2]) const { n[0] = n[1] = 4; }
};

struct SmoothVertex {
    int n;
    int GetNumEdges() const { return n; }
    int GetNumFaces() const { return n; }
    float GetSharpness() const { return 0.0f; }
    float *GetSharpnessPerEdge(float s[]) const
    {
        for (int i = 0; i < n; ++i) s[i] = 0.0f;
        return s;
    }
    float GetChildSharpness(const Sdc::Crease &) const { return 0.0f; }
    float *GetChildSharpnessPerEdge(const Sdc::Crease &, float s[]) const
    {
        return GetSharpnessPerEdge(s);
    }
};

/* A crease edge (infinitely sharp, its children too). */
struct CreaseEdge {
    int GetNumFaces() const { return 2; }
    float GetSharpness() const { return Sdc::Crease::SHARPNESS_INFINITE; }
    void GetChildSharpnesses(const Sdc::Crease &, float s[2]) const
    {
        s[0] = s[1] = Sdc::Crease::SHARPNESS_INFINITE;
    }
    void GetNumVerticesPerFace(int n[2]) const { n[0] = n[1] = 4; }
};

/* An interior vertex of n edges, some of them creases (sharp[i]: its i-th edge, counter-
 * clockwise as Vtr orders them, is infinitely sharp). Infinite sharpness stays infinite, so
 * its children's sharpness is its own. */
struct CreasedVertex {
    int n;
    const float *sharp;
    int GetNumEdges() const { return n; }
    int GetNumFaces() const { return n; }
    float GetSharpness() const { return 0.0f; }
    float *GetSharpnessPerEdge(float s[]) const
    {
        for (int i = 0; i < n; ++i) s[i] = sharp[i];
        return s;
    }
    float GetChildSharpness(const Sdc::Crease &) const { return 0.0f; }
    float *GetChildSharpnessPerEdge(const Sdc::Crease &, float s[]) const
    {
        return GetSharpnessPerEdge(s);
    }
};

/* One mask's weights: its vertices' (a face's corners, an edge's ends, or the vertex itself),
 * its edges' and its faces'. */
struct Weights {
    double v[4];
    double e[kDirectMaxValence], f[kDirectMaxValence];
    int ne, nf;
    bool centres; /* face weights apply to face points, not to the faces' opposite vertices */

    Mask mask() { return Mask(v, e, f); }
    void take(const Mask &m)
    {
        ne = m.GetNumEdgeWeights();
        nf = m.GetNumFaceWeights();
        centres = m.AreFaceWeightsForFaceCenters();
    }
};

/* The masks of one valence: the vertex rule, the limit position and the two limit tangents. */
struct ValenceMasks {
    bool ready;
    Weights rule, pos, tan1, tan2;
};

/* Every mask the direct path applies, from Sdc::Scheme, made once per valence met. */
class Masks {
public:
    Masks(const xyl_allocator *alloc, Sdc::SchemeType type)
        : by_valence_(alloc, kDirectMaxValence + 1), type_(type)
    {
    }
    bool ok() const { return by_valence_.get() != nullptr; }

    void init()
    {
        Mask e = edge_.mask();
        if (type_ == Sdc::SCHEME_LOOP) {
            Scheme<Sdc::SCHEME_LOOP>().ComputeEdgeVertexMask(SmoothEdge(), e, kSmooth, kSmooth);
        } else {
            Scheme<Sdc::SCHEME_CATMARK>().ComputeEdgeVertexMask(SmoothEdge(), e, kSmooth,
                                                                kSmooth);
            for (int n = 3; n <= 4; ++n) {
                Mask f = face_[n].mask();
                Scheme<Sdc::SCHEME_CATMARK>().ComputeFaceVertexMask(SmoothFace{n}, f);
                face_[n].take(f);
            }
        }
        edge_.take(e);
        Mask c = crease_edge_.mask();
        const Sdc::Crease::Rule crease = Sdc::Crease::RULE_CREASE;
        if (type_ == Sdc::SCHEME_LOOP)
            Scheme<Sdc::SCHEME_LOOP>().ComputeEdgeVertexMask(CreaseEdge(), c, crease, crease);
        else
            Scheme<Sdc::SCHEME_CATMARK>().ComputeEdgeVertexMask(CreaseEdge(), c, crease, crease);
        crease_edge_.take(c);
    }
    const Weights &edge() const { return edge_; }
    const Weights &crease_edge() const { return crease_edge_; }

    /* The vertex rule, or (limit) the limit position and tangent masks, of a vertex of n edges
     * some of which are creases (sharp: n values), into m. Vtr's rule for it follows from
     * the number of its crease edges; infinite creases leave its child the same rule. */
    void creased(int n, const float *sharp, bool limit, ValenceMasks *m) const
    {
        if (type_ == Sdc::SCHEME_LOOP)
            fill_creased<Sdc::SCHEME_LOOP>(n, sharp, limit, m);
        else
            fill_creased<Sdc::SCHEME_CATMARK>(n, sharp, limit, m);
    }
    const Weights &face(int n) const { return face_[n]; }
    const ValenceMasks &valence(int n)
    {
        ValenceMasks &m = by_valence_.get()[n];
        if (!m.ready) make(n, &m);
        return m;
    }

private:
    template <Sdc::SchemeType T> using Scheme = Sdc::Scheme<T>;
    static constexpr Sdc::Crease::Rule kSmooth = Sdc::Crease::RULE_SMOOTH;

    template <Sdc::SchemeType T> static void fill(int n, ValenceMasks *m)
    {
        Sdc::Options options;
        options.SetVtxBoundaryInterpolation(Sdc::Options::VTX_BOUNDARY_EDGE_AND_CORNER);
        const Scheme<T> scheme(options);
        Mask rule = m->rule.mask(), pos = m->pos.mask(), t1 = m->tan1.mask(),
             t2 = m->tan2.mask();
        scheme.ComputeVertexVertexMask(SmoothVertex{n}, rule, kSmooth, kSmooth);
        scheme.ComputeVertexLimitMask(SmoothVertex{n}, pos, t1, t2, kSmooth);
        m->rule.take(rule);
        m->pos.take(pos);
        m->tan1.take(t1);
        m->tan2.take(t2);
    }
    template <Sdc::SchemeType T>
    static void fill_creased(int n, const float *sharp, bool limit, ValenceMasks *m)
    {
        Sdc::Options options;
        options.SetVtxBoundaryInterpolation(Sdc::Options::VTX_BOUNDARY_EDGE_AND_CORNER);
        const Scheme<T> scheme(options);
        const CreasedVertex v{n, sharp};
        const Sdc::Crease::Rule rule =
            Sdc::Crease(options).DetermineVertexVertexRule(0.0f, n, sharp);
        if (!limit) {
            Mask r = m->rule.mask();
            scheme.ComputeVertexVertexMask(v, r, rule, rule);
            m->rule.take(r);
            return;
        }
        Mask pos = m->pos.mask(), t1 = m->tan1.mask(), t2 = m->tan2.mask();
        scheme.ComputeVertexLimitMask(v, pos, t1, t2, rule);
        m->pos.take(pos);
        m->tan1.take(t1);
        m->tan2.take(t2);
    }
    void make(int n, ValenceMasks *m) const
    {
        if (type_ == Sdc::SCHEME_LOOP)
            fill<Sdc::SCHEME_LOOP>(n, m);
        else
            fill<Sdc::SCHEME_CATMARK>(n, m);
        m->ready = true;
    }

    Buffer<ValenceMasks> by_valence_;
    Weights edge_, crease_edge_, face_[5];
    Sdc::SchemeType type_;
};

/* The base mesh as half-edges: corner c of face f is the half-edge from vert[c] to the next
 * corner's vertex. */
struct Base {
    int nv, nf, ne, corners;
    const int *size, *vert;
    Buffer<int> start;       /* nf + 1: each face's first corner */
    Buffer<int> face_of;     /* corner -> face */
    Buffer<int> twin;        /* corner -> the opposite half-edge */
    Buffer<int> edge;        /* corner -> edge, numbered as Far numbers them */
    Buffer<int> edge_corner; /* 2 per edge: its half-edge in the face that made it, then the twin */
    Buffer<int> ring_start;  /* nv + 1 */
    Buffer<int> ring;        /* each vertex's outgoing half-edges, counter-clockwise */
    Buffer<float> sharp;     /* ne: each edge's sharpness (a crease's infinite), or NULL */
    Buffer<uint8_t> on_crease; /* nv: the vertex has a crease edge (with sharp) */

    explicit Base(const xyl_allocator *alloc)
        : nv(0), nf(0), ne(0), corners(0), size(nullptr), vert(nullptr), start(alloc),
          face_of(alloc), twin(alloc), edge(alloc), edge_corner(alloc), ring_start(alloc),
          ring(alloc), sharp(alloc), on_crease(alloc)
    {
    }
    bool creased() const { return sharp.get() != nullptr; }
    int next(int c) const
    {
        const int f = face_of.get()[c];
        return c + 1 < start.get()[f + 1] ? c + 1 : start.get()[f];
    }
    int prev(int c) const
    {
        const int f = face_of.get()[c];
        return c > start.get()[f] ? c - 1 : start.get()[f + 1] - 1;
    }
    int head(int c) const { return vert[next(c)]; }
    int valence(int v) const { return ring_start.get()[v + 1] - ring_start.get()[v]; }
};

enum class Fit { YES, NO, NO_MEMORY };

/* Each vertex's outgoing half-edges in corner order (so the first lies in its lowest face). */
Fit collect_rings(Base *b)
{
    int *rs = b->ring_start.get(), *ring = b->ring.get();
    for (int c = 0; c < b->corners; ++c) ++rs[b->vert[c] + 1];
    for (int v = 0; v < b->nv; ++v) {
        const int n = rs[v + 1];
        if (n < 3 || n > kDirectMaxValence) return Fit::NO; /* unused, a spike, or a wide fan */
        rs[v + 1] = rs[v] + n;
    }
    for (int c = 0; c < b->corners; ++c) ring[rs[b->vert[c]]++] = c;
    for (int v = b->nv; v > 0; --v) rs[v] = rs[v - 1];
    rs[0] = 0;
    return Fit::YES;
}

/* Pairs every half-edge with its twin (exactly one, running the other way: else the mesh has a
 * boundary, a flipped face or an edge in three faces) and numbers the edges in the order the
 * faces first meet them, as Vtr::Level::completeTopologyFromFaceVertices does. */
Fit pair_edges(Base *b)
{
    const int *rs = b->ring_start.get(), *ring = b->ring.get();
    int *twin = b->twin.get(), *edge = b->edge.get(), *ec = b->edge_corner.get();
    int *head = edge; /* each half-edge's head vertex until the edges are numbered */
    for (int f = 0; f < b->nf; ++f) {
        const int s = b->start.get()[f], e = b->start.get()[f + 1];
        for (int c = s; c + 1 < e; ++c) head[c] = b->vert[c + 1];
        head[e - 1] = b->vert[s];
    }
    for (int c = 0; c < b->corners; ++c) {
        const int from = b->vert[c], to = head[c];
        int found = 0;
        for (int i = rs[to]; i < rs[to + 1]; ++i)
            if (head[ring[i]] == from) twin[c] = ring[i], ++found;
        if (found != 1) return Fit::NO;
    }
    for (int c = 0; c < b->corners; ++c) {
        if (twin[c] < c) {
            edge[c] = edge[twin[c]];
            continue;
        }
        edge[c] = b->ne;
        ec[2 * b->ne] = c;
        ec[2 * b->ne + 1] = twin[c];
        ++b->ne;
    }
    return Fit::YES;
}

/* Orders each vertex's half-edges counter-clockwise from the one in its lowest face, as
 * Vtr::Level::orderVertexFacesAndEdges does; a vertex whose faces form more than one fan
 * does not fit. */
Fit order_rings(Base *b)
{
    const int *rs = b->ring_start.get(), *twin = b->twin.get();
    int *ring = b->ring.get();
    for (int v = 0; v < b->nv; ++v) {
        const int first = ring[rs[v]], n = b->valence(v);
        int h = first;
        for (int i = 0; i < n; ++i) {
            if (i > 0 && h == first) return Fit::NO;
            ring[rs[v] + i] = h;
            h = twin[b->prev(h)];
        }
        if (h != first) return Fit::NO;
    }
    return Fit::YES;
}

/* Marks the creases' edges infinitely sharp. On the closed manifold the direct path takes, an
 * edge (a, b) is a half-edge from a to b in a's ring; a crease without one is no edge, and its
 * index goes to *bad. */
Fit mark_creases(Base *b, const Creases &c, size_t *bad)
{
    if (c.count == 0) return Fit::YES;
    if (!b->sharp.allocate(size_t(b->ne)) || !b->on_crease.allocate(size_t(b->nv)))
        return Fit::NO_MEMORY;
    const int *rs = b->ring_start.get(), *ring = b->ring.get();
    for (size_t i = 0; i < c.count; ++i) {
        const int from = int(c.pairs[2 * i]), to = int(c.pairs[2 * i + 1]);
        int j = rs[from];
        while (j < rs[from + 1] && b->head(ring[j]) != to) ++j;
        if (j == rs[from + 1]) {
            *bad = i;
            return Fit::NO;
        }
        b->sharp.get()[b->edge.get()[ring[j]]] = Sdc::Crease::SHARPNESS_INFINITE;
        b->on_crease.get()[from] = b->on_crease.get()[to] = 1;
    }
    return Fit::YES;
}

/* Builds b from the control mesh, or says why the direct path does not apply. */
Fit build_base(int vertices, const Control &control, Base *b)
{
    b->nv = vertices;
    b->nf = control.faces;
    b->size = control.counts.get();
    b->vert = control.indices.get();
    if (!b->start.allocate(size_t(b->nf) + 1)) return Fit::NO_MEMORY;
    int *start = b->start.get();
    for (int f = 0; f < b->nf; ++f) start[f + 1] = start[f] + b->size[f];
    b->corners = start[b->nf];
    const size_t corners = size_t(b->corners);
    /* each written in full before it is read; ring_start counts from zero */
    if (!b->face_of.allocate_unset(corners) || !b->twin.allocate_unset(corners) ||
        !b->edge.allocate_unset(corners) || !b->edge_corner.allocate_unset(corners) ||
        !b->ring_start.allocate(size_t(b->nv) + 1) || !b->ring.allocate_unset(corners))
        return Fit::NO_MEMORY;
    for (int f = 0; f < b->nf; ++f)
        for (int c = start[f]; c < start[f + 1]; ++c) b->face_of.get()[c] = f;
    Fit fit = collect_rings(b);
    if (fit == Fit::YES) fit = pair_edges(b);
    if (fit == Fit::YES) fit = order_rings(b);
    return fit;
}

/* Level 1 as the direct path numbers it: vertex points, face points (Catmark), edge points;
 * Catmark's child faces are the base corners (child h of face f is the quad at corner h), Loop's
 * are 4 per triangle, the three corners' then the middle one. */
class Direct {
public:
    Direct(const Base &b, bool loop) : b_(b), loop_(loop) {}
    int vertices() const { return b_.nv + b_.ne + (loop_ ? 0 : b_.nf); }
    int faces() const { return loop_ ? 4 * b_.nf : b_.corners; }
    int corners() const { return loop_ ? 3 : 4; }
    int V(int v) const { return v; }
    int F(int f) const { return b_.nv + f; }
    int E(int e) const { return b_.nv + (loop_ ? 0 : b_.nf) + e; }
    int edge_of(int c) const { return E(b_.edge.get()[c]); }
    int child(int c) const /* Loop: the child face at corner c */
    {
        const int f = b_.face_of.get()[c];
        return 4 * f + (c - b_.start.get()[f]);
    }

    /* Level-1 vertex u's neighbourhood, counter-clockwise from where Vtr starts it: the far ends
     * of its edges (edge), the vertices opposite it in its faces (Catmark; opp) and its faces
     * (face). Returns its valence. */
    int ring(int u, int *edge, int *opp, int *face) const
    {
        if (u < b_.nv) return vertex_ring(u, edge, opp, face);
        if (!loop_ && u < b_.nv + b_.nf) return face_ring(u - b_.nv, edge, opp, face);
        return edge_ring(u - b_.nv - (loop_ ? 0 : b_.nf), edge, opp, face);
    }

    /* The sharpness of level-1 vertex u's edges, in ring()'s order, into sharp; returns how
     * many are creases. The children of a crease's edge are creases: the two halves of it
     * (an edge point's first and opposite edges) and each end's edge along it. */
    int sharpness(int u, float *sharp) const
    {
        if (!b_.creased() || (!loop_ && u >= b_.nv && u < b_.nv + b_.nf)) return 0;
        const float *es = b_.sharp.get();
        int count = 0;
        if (u < b_.nv) {
            if (!b_.on_crease.get()[u]) return 0;
            const int s = b_.ring_start.get()[u], n = b_.valence(u);
            for (int i = 0; i < n; ++i) {
                sharp[i] = es[b_.edge.get()[b_.ring.get()[s + i]]];
                count += sharp[i] > 0.0f;
            }
            return count;
        }
        const float e = es[u - b_.nv - (loop_ ? 0 : b_.nf)];
        const int n = loop_ ? 6 : 4, half = n / 2;
        for (int i = 0; i < n; ++i) sharp[i] = i % half == 0 ? e : 0.0f;
        return e > 0.0f ? 2 : 0;
    }

    /* The child faces' corners, each face's winding kept. */
    void write_faces(uint32_t *out) const
    {
        for (int f = 0; f < b_.nf; ++f) loop_ ? loop_faces(f, out) : quad_faces(f, out);
    }

private:
    int vertex_ring(int v, int *edge, int *opp, int *face) const
    {
        const int s = b_.ring_start.get()[v], n = b_.valence(v);
        for (int i = 0; i < n; ++i) {
            const int h = b_.ring.get()[s + i];
            edge[i] = edge_of(h);
            opp[i] = loop_ ? -1 : F(b_.face_of.get()[h]);
            face[i] = loop_ ? child(h) : h;
        }
        return n;
    }
    int face_ring(int f, int *edge, int *opp, int *face) const
    {
        const int s = b_.start.get()[f], n = b_.size[f];
        for (int j = 0; j < n; ++j) {
            edge[j] = edge_of(b_.prev(s + j));
            opp[j] = V(b_.vert[s + j]);
            face[j] = s + j;
        }
        return n;
    }
    int edge_ring(int e, int *edge, int *opp, int *face) const
    {
        const int ca = b_.edge_corner.get()[2 * e], cb = b_.edge_corner.get()[2 * e + 1];
        const int v0 = V(b_.vert[ca]), v1 = V(b_.vert[cb]);
        if (loop_) {
            const int fa = b_.face_of.get()[ca], fb = b_.face_of.get()[cb];
            const int e6[6] = {v1, edge_of(b_.next(ca)), edge_of(b_.prev(ca)),
                               v0, edge_of(b_.next(cb)), edge_of(b_.prev(cb))};
            const int f6[6] = {child(b_.next(ca)), 4 * fa + 3, child(ca),
                               child(b_.next(cb)), 4 * fb + 3, child(cb)};
            for (int i = 0; i < 6; ++i) edge[i] = e6[i], opp[i] = -1, face[i] = f6[i];
            return 6;
        }
        const int e4[4] = {v1, F(b_.face_of.get()[ca]), v0, F(b_.face_of.get()[cb])};
        const int o4[4] = {edge_of(b_.next(ca)), edge_of(b_.prev(ca)), edge_of(b_.next(cb)),
                           edge_of(b_.prev(cb))};
        const int f4[4] = {b_.next(ca), ca, b_.next(cb), cb};
        for (int i = 0; i < 4; ++i) edge[i] = e4[i], opp[i] = o4[i], face[i] = f4[i];
        return 4;
    }
    /* Vtr's QuadRefinement: the child at corner j of a quad starts at position j. */
    void quad_faces(int f, uint32_t *out) const
    {
        const int s = b_.start.get()[f], n = b_.size[f];
        for (int j = 0; j < n; ++j) {
            const int h = s + j, r = n == 4 ? j : 0;
            uint32_t *q = out + 4 * size_t(h);
            q[r] = uint32_t(V(b_.vert[h]));
            q[(r + 1) & 3] = uint32_t(edge_of(h));
            q[(r + 2) & 3] = uint32_t(F(f));
            q[(r + 3) & 3] = uint32_t(edge_of(b_.prev(h)));
        }
    }
    /* Vtr's TriRefinement. */
    void loop_faces(int f, uint32_t *out) const
    {
        const int s = b_.start.get()[f];
        const uint32_t a = uint32_t(V(b_.vert[s])), b = uint32_t(V(b_.vert[s + 1])),
                       c = uint32_t(V(b_.vert[s + 2]));
        const uint32_t e0 = uint32_t(edge_of(s)), e1 = uint32_t(edge_of(s + 1)),
                       e2 = uint32_t(edge_of(s + 2));
        const uint32_t t[12] = {a, e0, e2, e0, b, e1, e2, e1, c, e1, e2, e0};
        std::memcpy(out + 12 * size_t(f), t, sizeof t);
    }

    const Base &b_;
    bool loop_;
};

/* Level-1 control points, with PrimvarRefiner::Interpolate's masks and order of sums: face
 * points, edge points (their ends, then their faces' points or opposite vertices), vertex
 * points (face points, far ends of the edges, the vertex itself). */
void direct_points(const Base &b, const Direct &d, bool loop, Masks &masks, const Point3 *p0,
                   Point3 *p1)
{
    const int *vert = b.vert, *ring = b.ring.get(), *face_of = b.face_of.get();
    if (!loop)
        for (int f = 0; f < b.nf; ++f) {
            const int s = b.start.get()[f], n = b.size[f];
            const double *w = masks.face(n).v;
            Point3 &dst = p1[d.F(f)];
            dst.Clear();
            for (int j = 0; j < n; ++j) dst.AddWithWeight(p0[vert[s + j]], w[j]);
        }
    for (int e = 0; e < b.ne; ++e) {
        const int ca = b.edge_corner.get()[2 * e], cb = b.edge_corner.get()[2 * e + 1];
        const Weights &we =
            b.creased() && b.sharp.get()[e] > 0.0f ? masks.crease_edge() : masks.edge();
        Point3 &dst = p1[d.E(e)];
        dst.Clear();
        dst.AddWithWeight(p0[vert[ca]], we.v[0]);
        dst.AddWithWeight(p0[vert[cb]], we.v[1]);
        if (we.nf == 0) continue;
        if (we.centres) {
            dst.AddWithWeight(p1[d.F(face_of[ca])], we.f[0]);
            dst.AddWithWeight(p1[d.F(face_of[cb])], we.f[1]);
        } else { /* Loop: the vertex opposite the edge in each triangle */
            dst.AddWithWeight(p0[vert[b.prev(ca)]], we.f[0]);
            dst.AddWithWeight(p0[vert[b.prev(cb)]], we.f[1]);
        }
    }
    float sharp[kDirectMaxValence];
    ValenceMasks creased;
    for (int v = 0; v < b.nv; ++v) {
        const int s = b.ring_start.get()[v], n = b.valence(v);
        const bool crease = d.sharpness(d.V(v), sharp) > 0;
        if (crease) masks.creased(n, sharp, false, &creased);
        const Weights &w = crease ? creased.rule : masks.valence(n).rule;
        Point3 &dst = p1[d.V(v)];
        dst.Clear();
        for (int i = 0; i < w.nf; ++i) dst.AddWithWeight(p1[d.F(face_of[ring[s + i]])], w.f[i]);
        for (int i = 0; i < w.ne; ++i) dst.AddWithWeight(p0[b.head(ring[s + i])], w.e[i]);
        dst.AddWithWeight(p0[v], w.v[0]);
    }
}

/* PrimvarRefiner::Limit's sums for level-1 vertex u with a mask of its valence: the opposite
 * vertices' weights, the edges' far ends', then its own. */
/* The limit position and tangents of level-1 vertex u: three masks of one shape applied in one
 * sweep over its neighbours, each sum in PrimvarRefiner::Limit's order (opposite vertices,
 * edges' far ends, then u itself). NF, NE: the weights' counts, fixed for the regular cases. */
template <int NF, int NE>
[[gnu::always_inline]] inline void limit_sums(const ValenceMasks &m, int nf, int ne,
                                              const Point3 *p, int u, const int *edge,
                                              const int *opp, Point3 out[3])
{
    const Weights *w[3] = {&m.pos, &m.tan1, &m.tan2};
    for (int k = 0; k < 3; ++k) out[k].Clear();
    for (int i = 0; i < (NF < 0 ? nf : NF); ++i) {
        const Point3 q = p[opp[i]];
        for (int k = 0; k < 3; ++k) out[k].AddWithWeight(q, w[k]->f[i]);
    }
    for (int i = 0; i < (NE < 0 ? ne : NE); ++i) {
        const Point3 q = p[edge[i]];
        for (int k = 0; k < 3; ++k) out[k].AddWithWeight(q, w[k]->e[i]);
    }
    for (int k = 0; k < 3; ++k) out[k].AddWithWeight(p[u], w[k]->v[0]);
}

/* The same, for any mask (one sum at a time where the three masks differ in shape). */
void limit_point(const ValenceMasks &m, const Point3 *p, int u, const int *edge, const int *opp,
                 Point3 out[3])
{
    const int nf = m.pos.nf, ne = m.pos.ne;
    const bool same = m.tan1.nf == nf && m.tan2.nf == nf && m.tan1.ne == ne && m.tan2.ne == ne;
    if (same && nf == 4 && ne == 4) return limit_sums<4, 4>(m, nf, ne, p, u, edge, opp, out);
    if (same && nf == 0 && ne == 6) return limit_sums<0, 6>(m, nf, ne, p, u, edge, opp, out);
    if (same) return limit_sums<-1, -1>(m, nf, ne, p, u, edge, opp, out);
    const Weights *w[3] = {&m.pos, &m.tan1, &m.tan2};
    for (int k = 0; k < 3; ++k) {
        out[k].Clear();
        for (int i = 0; i < w[k]->nf; ++i) out[k].AddWithWeight(p[opp[i]], w[k]->f[i]);
        for (int i = 0; i < w[k]->ne; ++i) out[k].AddWithWeight(p[edge[i]], w[k]->e[i]);
        out[k].AddWithWeight(p[u], w[k]->v[0]);
    }
}

/* The limit positions of the level-1 points p1 into lim (and, as floats, positions) with the
 * cross products of the limit tangents (tn), then the limit normals, oriented by the faces
 * around each vertex at their limit positions as project_to_limit orients them (each face's
 * normal made once, into p1, which is no longer needed then and has room for one per face). */
void direct_limit(const Direct &d, Masks &masks, Point3 *p1, const uint32_t *faces, Point3 *lim,
                  Point3 *tn, xyl_vec3 *positions, xyl_vec3 *normals)
{
    int edge[kDirectMaxValence], opp[kDirectMaxValence], face[kDirectMaxValence];
    float sharp[kDirectMaxValence];
    ValenceMasks creased;
    for (int u = 0; u < d.vertices(); ++u) {
        const int n = d.ring(u, edge, opp, face);
        const bool crease = d.sharpness(u, sharp) > 0;
        if (crease) masks.creased(n, sharp, true, &creased);
        const ValenceMasks &m = crease ? creased : masks.valence(n);
        Point3 sums[3]; /* position, tangents */
        limit_point(m, p1, u, edge, opp, sums);
        lim[u] = sums[0];
        tn[u] = tangent_normal(sums[1], sums[2]);
        positions[u] = xyl_vec3{static_cast<float>(sums[0].x), static_cast<float>(sums[0].y),
                                static_cast<float>(sums[0].z)};
    }
    const size_t corners = size_t(d.corners());
    Point3 *fn = p1;
    for (size_t f = 0; f < size_t(d.faces()); ++f)
        fn[f] = face_normal(faces + f * corners, int(corners), lim);
    for (int u = 0; u < d.vertices(); ++u) {
        const int n = d.ring(u, edge, opp, face);
        Point3 ref = {0.0, 0.0, 0.0};
        for (int i = 0; i < n; ++i) ref.AddWithWeight(fn[face[i]], 1.0);
        normals[u] = oriented_normal(tn[u], ref);
    }
}

/* Face branches from the parent face, vertex branches by the rules of assign_vertex_branches. */
void direct_branches(const Base &b, const Direct &d, bool loop, const xyl__mesh_arrays *in,
                     const uint32_t *face_branch, Refined *out)
{
    uint32_t *fb = out->face_branches.get(), *vb = out->branch_ids.get();
    for (int f = 0; f < b.nf; ++f) {
        const int kids = loop ? 4 : b.size[f], first = loop ? 4 * f : b.start.get()[f];
        for (int i = 0; i < kids; ++i) fb[first + i] = face_branch[f];
    }
    for (int v = 0; v < b.nv; ++v) vb[d.V(v)] = in->branch_ids ? in->branch_ids[v] : 0;
    for (int e = 0; e < b.ne; ++e) {
        const int ca = b.edge_corner.get()[2 * e], cb = b.edge_corner.get()[2 * e + 1];
        const int faces[2] = {b.face_of.get()[ca], b.face_of.get()[cb]};
        const int ends[2] = {b.vert[ca], b.vert[cb]};
        vb[d.E(e)] = edge_branch(faces, 2, ends, in->branch_ids, face_branch);
    }
    if (loop) return;
    for (int f = 0; f < b.nf; ++f) vb[d.F(f)] = face_branch[f];
}

/* The UV a child corner takes in its parent face's frame: Catmark's child at corner j holds
 * the corner, the edge after it, the centre and the edge before it (kind k = 0..3); Loop's
 * children hold the corners and edges of the table in Direct::loop_faces. */
Point2 catmark_corner_uv(const FaceFrame &frame, int j, int k)
{
    switch (k) {
    case 0: return frame.corner[j];
    case 1: return frame.edge[j];
    case 2: return frame.centre;
    default: return frame.edge[(j + frame.n - 1) % frame.n];
    }
}

Point2 loop_corner_uv(const FaceFrame &frame, int child, int pos)
{
    /* corner c as c, edge e as 3 + e, per child face and position */
    static const int8_t part[4][3] = {{0, 3, 5}, {3, 1, 4}, {5, 4, 2}, {4, 5, 3}};
    const int x = part[child][pos];
    return x < 3 ? frame.corner[x] : frame.edge[x - 3];
}

/* interpolate_uvs for the direct path: the same rule, each (parent face, level-1 vertex) pair
 * offered once in face order (interpolate_uvs offers a pair once per child face that holds it,
 * and repeats change nothing), and each child corner's UV read from its place in the parent
 * face rather than searched for. */
bool direct_uvs(const Base &b, const Direct &d, bool loop, const xyl__mesh_arrays *in,
                const Control &control, const xyl_allocator *alloc, Refined *out)
{
    const size_t n1 = size_t(d.vertices());
    Buffer<Point2> uv(alloc);
    Buffer<double> narrowest(alloc); /* the span of the parent face uv[] came from */
    Buffer<uint8_t> seen(alloc, n1); /* uv and narrowest are read only where this is set */
    if (!uv.allocate_unset(n1) || !narrowest.allocate_unset(n1) || !seen.get()) return false;
    const uint8_t *parent_wraps = control.wraps.get();
    Point2 *own = uv.get();
    double *best = narrowest.get();
    uint8_t *taken = seen.get();
    auto offer = [&](int v, const Point2 &c, double span) {
        if (!taken[v] || span < best[v] || (span == best[v] && c.u < own[v].u))
            own[v] = c, best[v] = span;
        taken[v] = 1;
    };
    for (int f = 0; f < b.nf; ++f) {
        const int s = b.start.get()[f];
        const FaceFrame frame(FaceFrame::Consecutive(), b.vert + s, b.size[f], parent_wraps[f],
                              in->uvs);
        for (int c = 0; c < frame.n; ++c) {
            offer(d.V(b.vert[s + c]), frame.corner[c], frame.span);
            offer(d.edge_of(s + c), frame.edge[c], frame.span);
        }
        if (!loop) offer(d.F(f), frame.centre, frame.span);
    }
    const uint32_t *faces = out->faces.get();
    uint8_t *wraps = out->wraps.get();
    for (int f = 0; f < b.nf; ++f) {
        const int s = b.start.get()[f];
        const FaceFrame frame(FaceFrame::Consecutive(), b.vert + s, b.size[f], parent_wraps[f],
                              in->uvs);
        const int kids = loop ? 4 : frame.n, first = loop ? 4 * f : s;
        for (int i = 0; i < kids; ++i) {
            const size_t kid = size_t(first + i);
            uint8_t bits = 0;
            for (int pos = 0; pos < d.corners(); ++pos) {
                const uint32_t v = faces[kid * size_t(d.corners()) + size_t(pos)];
                const int k = frame.n == 4 ? (pos - i + 4) & 3 : pos;
                const Point2 c =
                    loop ? loop_corner_uv(frame, i, pos) : catmark_corner_uv(frame, i, k);
                if (c.u - own[v].u >= 0.5) bits = static_cast<uint8_t>(bits | 1u << pos);
            }
            wraps[kid] = bits;
        }
    }
    for (size_t v = 0; v < n1; ++v) {
        out->uvs.get()[2 * v] = static_cast<float>(own[v].u);
        out->uvs.get()[2 * v + 1] = static_cast<float>(own[v].v);
    }
    return true;
}

/* One level by the direct path into fine (allocated for d's counts). */
bool direct_level(const Base &b, bool loop, bool limit, const xyl__mesh_arrays *in,
                   const Control &control, const xyl_allocator *alloc, Refined *fine)
{
    const Direct d(b, loop);
    Masks masks(alloc, loop ? Sdc::SCHEME_LOOP : Sdc::SCHEME_CATMARK);
    const size_t n1 = size_t(d.vertices());
    /* p1 is written in full below; with the limit it later holds the faces' normals too */
    const size_t f1 = size_t(d.faces()), p1_size = limit && f1 > n1 ? f1 : n1;
    Buffer<Point3> p0(alloc), p1(alloc);
    if (!masks.ok() || !p0.allocate_unset(size_t(b.nv)) || !p1.allocate_unset(p1_size))
        return false;
    masks.init();
    d.write_faces(fine->faces.get());
    for (int v = 0; v < b.nv; ++v) {
        const xyl_vec3 p = in->positions[v];
        p0.get()[v] = Point3{p.x, p.y, p.z};
    }
    direct_points(b, d, loop, masks, p0.get(), p1.get());
    if (limit) {
        Buffer<Point3> lim(alloc), tn(alloc); /* written in full by direct_limit */
        if (!lim.allocate_unset(n1) || !tn.allocate_unset(n1)) return false;
        direct_limit(d, masks, p1.get(), fine->faces.get(), lim.get(), tn.get(),
                     fine->positions.get(), fine->normals.get());
    } else {
        for (size_t v = 0; v < n1; ++v)
            fine->positions.get()[v] = xyl_vec3{static_cast<float>(p1.get()[v].x),
                                                static_cast<float>(p1.get()[v].y),
                                                static_cast<float>(p1.get()[v].z)};
    }
    direct_branches(b, d, loop, in, control.branches.get(), fine);
    return direct_uvs(b, d, loop, in, control, alloc, fine);
}

/* The direct path's counts, checked against the limits, then its level handed to out. */
xyl_result refine_direct(const Base &b, bool loop, bool limit, const Limits &lim,
                         const xyl__mesh_arrays *in, const Control &control,
                         const xyl_allocator *alloc, xyl__mesh_arrays *out, xyl_diag *diag)
{
    const uint64_t v1 = uint64_t(b.nv) + uint64_t(b.ne) + (loop ? 0u : uint64_t(b.nf));
    const uint64_t f1 = loop ? 4u * uint64_t(b.nf) : uint64_t(b.corners);
    xyl_result res = check_limits(v1, f1, lim, diag);
    if (res) return res;
    if (v1 > kIntMax || f1 > kIntMax)
        return xyl__fail(diag, XYL_ERR_UNSUPPORTED, 0, 0, -1,
                         "%llu vertices or %llu faces exceed OpenSubdiv's int indices",
                         static_cast<unsigned long long>(v1), static_cast<unsigned long long>(f1));
    Refined fine(alloc, static_cast<size_t>(v1), static_cast<size_t>(f1), loop ? 3 : 4, limit);
    if (!fine.ok(limit) || !direct_level(b, loop, limit, in, control, alloc, &fine))
        return xyl__fail(diag, XYL_ERR_OUT_OF_MEMORY, 0, 0, -1,
                         "out of memory for the refined mesh");
    return hand_out(&fine, v1, f1, loop, alloc, out, diag);
}


xyl_result refine(const xyl__mesh_arrays *in, xyl_subdivision scheme, bool limit,
                  const Limits &lim, xyl__subdivide_path path, const Creases &creases,
                  const xyl_allocator *alloc, xyl__mesh_arrays *out, xyl_diag *diag)
{
    const bool loop = scheme == XYL_SUBDIVIDE_LOOP;
    const uint64_t far_faces = loop ? 2u * uint64_t(in->quad_count) + in->triangle_count
                                    : uint64_t(face_count(in));
    const uint64_t corners = 4u * uint64_t(in->quad_count) + 3u * uint64_t(in->triangle_count) +
                             (loop ? 2u * uint64_t(in->quad_count) : 0u);
    if (in->vertex_count > kIntMax || far_faces > kIntMax || corners > kIntMax)
        return xyl__fail(diag, XYL_ERR_UNSUPPORTED, 0, 0, -1,
                         "the mesh is too large for OpenSubdiv's int indices");
    if (creases.count > kIntMax)
        return xyl__fail(diag, XYL_ERR_UNSUPPORTED, 0, 0, -1,
                         "%zu creases are too many for OpenSubdiv's int counts", creases.count);
    Control control(alloc, static_cast<size_t>(far_faces), static_cast<size_t>(corners));
    if (!control.ok())
        return xyl__fail(diag, XYL_ERR_OUT_OF_MEMORY, 0, 0, -1, "out of memory for the topology");
    fill_control(in, loop, &control);
    if (path != XYL__SUBDIVIDE_FAR) {
        Base base(alloc);
        Fit fit = build_base(static_cast<int>(in->vertex_count), control, &base);
        size_t bad = 0;
        const Fit marked = fit == Fit::YES ? mark_creases(&base, creases, &bad) : fit;
        if (fit == Fit::NO_MEMORY || marked == Fit::NO_MEMORY)
            return xyl__fail(diag, XYL_ERR_OUT_OF_MEMORY, 0, 0, -1,
                             "out of memory for the topology");
        if (fit == Fit::YES && marked == Fit::NO) return not_an_edge(creases, bad, diag);
        if (fit == Fit::YES)
            return refine_direct(base, loop, limit, lim, in, control, alloc, out, diag);
        if (path == XYL__SUBDIVIDE_DIRECT)
            return xyl__fail(diag, XYL_ERR_UNSUPPORTED, 0, 0, -1,
                             "the direct path needs a closed oriented manifold whose vertices "
                             "are each in one fan of 3 to %d faces", kDirectMaxValence);
    }
    const xyl_result checked =
        check_creases(control, static_cast<int>(in->vertex_count), creases, alloc, diag);
    if (checked) return checked;
    std::unique_ptr<Refiner> r = create_refiner(loop ? Sdc::SCHEME_LOOP : Sdc::SCHEME_CATMARK,
                                                static_cast<int>(in->vertex_count), control,
                                                creases, alloc);
    if (!r)
        return xyl__fail(diag, XYL_ERR_UNSUPPORTED, 0, 0, -1,
                         "OpenSubdiv refused the topology (e.g. a vertex in more than 65535 "
                         "edges)");
    /* One level's counts follow from the base level: check them before refining. */
    const Far::TopologyLevel &base = r->GetLevel(0);
    const uint64_t v1 = uint64_t(base.GetNumVertices()) + uint64_t(base.GetNumEdges()) +
                        (loop ? 0u : uint64_t(base.GetNumFaces()));
    const uint64_t f1 =
        loop ? 4u * uint64_t(base.GetNumFaces()) : uint64_t(base.GetNumFaceVertices());
    xyl_result res = check_limits(v1, f1, lim, diag);
    if (res) return res;
    if (v1 > kIntMax || f1 > kIntMax) /* Far's indices are int (and ours uint32_t) */
        return xyl__fail(diag, XYL_ERR_UNSUPPORTED, 0, 0, -1,
                         "%llu vertices or %llu faces exceed OpenSubdiv's int indices",
                         static_cast<unsigned long long>(v1), static_cast<unsigned long long>(f1));
    Refiner::UniformOptions uniform(1);
    uniform.fullTopologyInLastLevel = limit; /* Limit() and the normals walk level 1 */
    r->RefineUniform(uniform);
    if (uint64_t(r->GetLevel(1).GetNumVertices()) != v1 ||
        uint64_t(r->GetLevel(1).GetNumFaces()) != f1)
        return xyl__fail(diag, XYL_ERR_UNSUPPORTED, 0, 0, -1,
                         "OpenSubdiv refined to unexpected counts (non-manifold input?)");
    const int corners1 = loop ? 3 : 4;
    Refined fine(alloc, static_cast<size_t>(v1), static_cast<size_t>(f1), corners1, limit);
    FarLevels levels(*r, !loop, alloc);
    if (!fine.ok(limit) || !interpolate_positions(*r, in, alloc, &fine) ||
        !interpolate_uvs(levels, in, control, alloc, &fine))
        return xyl__fail(diag, XYL_ERR_OUT_OF_MEMORY, 0, 0, -1,
                         "out of memory for the refined mesh");
    const uint32_t *parent_branch = control.branches.get();
    uint32_t *child_branch = fine.face_branches.get();
    DoubleRefiner(*r).InterpolateFaceUniform(1, parent_branch, child_branch);
    assign_vertex_branches(*r, in, parent_branch, !loop, fine.branch_ids.get());
    copy_faces(*r, corners1, fine.faces.get());
    return hand_out(&fine, v1, f1, loop, alloc, out, diag);
}

/* A scheme from C may hold any value of the enum's underlying type; in C++ loading an enum
 * outside its declared range is undefined, so its bytes are read as an integer first. */
bool read_scheme(const xyl_subdivision *stored, xyl_subdivision *scheme)
{
    std::underlying_type<xyl_subdivision>::type raw;
    static_assert(sizeof raw == sizeof *stored, "an enum and its underlying type");
    std::memcpy(&raw, stored, sizeof raw);
    switch (raw) {
    case XYL_SUBDIVIDE_NONE: *scheme = XYL_SUBDIVIDE_NONE; return true;
    case XYL_SUBDIVIDE_CATMARK: *scheme = XYL_SUBDIVIDE_CATMARK; return true;
    case XYL_SUBDIVIDE_LOOP: *scheme = XYL_SUBDIVIDE_LOOP; return true;
    default: return false;
    }
}

xyl_result unknown_scheme(const xyl_subdivision *stored, xyl_diag *diag)
{
    std::underlying_type<xyl_subdivision>::type raw;
    std::memcpy(&raw, stored, sizeof raw);
    return xyl__fail(diag, XYL_ERR_INVALID_ARGUMENT, 0, 0, -1, "unknown subdivision scheme %lld",
                     static_cast<long long>(raw));
}

xyl_result subdivide(const xyl__mesh_arrays *in, xyl_subdivision scheme, bool limit,
                     const xyl_mesh_limits *limits, xyl__subdivide_path path,
                     const Creases &creases, const xyl_allocator *alloc, xyl__mesh_arrays *out,
                     xyl_diag *diag)
{
    xyl_result r = validate_input(in, diag);
    if (r) return r;
    if (creases.count && !creases.pairs)
        return xyl__fail(diag, XYL_ERR_INVALID_ARGUMENT, 0, 0, -1,
                         "%zu creases without their vertex pairs", creases.count);
    r = check_crease_ends(in, creases, diag);
    if (r) return r;
    const Limits lim = effective_limits(limits);
    if (scheme == XYL_SUBDIVIDE_NONE || face_count(in) == 0) {
        r = check_limits(in->vertex_count, face_count(in), lim, diag);
        if (r) return r;
        return copy_mesh(in, scheme == XYL_SUBDIVIDE_NONE, alloc, out, diag);
    }
    return refine(in, scheme, limit, lim, path, creases, alloc, out, diag);
}

/* A closed prism of kRings k-gon rings of radius 1 along z, one unit apart, capped at both
 * ends, every face counter-clockwise seen from outside; refined by Catmull-Clark, or for Loop
 * with each band quad (a, b, c, d) split into (a, b, c), (a, c, d) as the mesher's meshes are,
 * and fan caps. Buffers, not std::vector: std:: template code keeps default visibility and
 * would be exported. */
constexpr int kRings = 9;

struct Prism {
    int k;
    bool loop;
    Buffer<Point3> points;
    Buffer<int> counts, indices;
    std::unique_ptr<Refiner> refiner;
    Far::Index probe; /* ring vertex in the middle of the prism */

    Prism(int k_, bool loop_)
        : k(k_), loop(loop_), points(nullptr, size_t(k_) * kRings),
          counts(nullptr, faces(k_, loop_)),
          indices(nullptr, loop_ ? 3 * faces(k_, loop_) : 4 * size_t(k_) * (kRings - 1) + 2 * size_t(k_)),
          probe((kRings / 2) * k_)
    {
    }
    static size_t faces(int k, bool loop)
    {
        return loop ? 2 * size_t(k) * (kRings - 1) + 2 * size_t(k - 2) : size_t(k) * (kRings - 1) + 2;
    }
};

/* A cap as one k-gon (Catmark) or as a fan of triangles (Loop), corners in the order given. */
void put_cap(const int *corner, int k, bool loop, int **idx, int **count)
{
    if (!loop) {
        for (int i = 0; i < k; ++i) *(*idx)++ = corner[i];
        *(*count)++ = k;
        return;
    }
    for (int i = 1; i + 1 < k; ++i) {
        *(*idx)++ = corner[0], *(*idx)++ = corner[i], *(*idx)++ = corner[i + 1];
        *(*count)++ = 3;
    }
}

bool make_prism(Prism *p)
{
    const int k = p->k;
    if (!p->points.get() || !p->counts.get() || !p->indices.get()) throw std::bad_alloc();
    const double step = 2.0 * XYL__PI / k;
    for (int j = 0; j < kRings; ++j)
        for (int i = 0; i < k; ++i)
            p->points.get()[j * k + i] = Point3{std::cos(step * i), std::sin(step * i), double(j)};
    int *idx = p->indices.get(), *count = p->counts.get();
    for (int j = 0; j + 1 < kRings; ++j)
        for (int i = 0; i < k; ++i) {
            int a = j * k + i, b = j * k + (i + 1) % k;
            if (p->loop) {
                *idx++ = a, *idx++ = b, *idx++ = b + k, *idx++ = a, *idx++ = b + k, *idx++ = a + k;
                *count++ = 3, *count++ = 3;
            } else {
                *idx++ = a, *idx++ = b, *idx++ = b + k, *idx++ = a + k;
                *count++ = 4;
            }
        }
    Buffer<int> corner(nullptr, size_t(k));
    if (!corner.get()) throw std::bad_alloc();
    for (int i = 0; i < k; ++i) corner.get()[i] = k - 1 - i; /* bottom cap faces -z */
    put_cap(corner.get(), k, p->loop, &idx, &count);
    for (int i = 0; i < k; ++i) corner.get()[i] = (kRings - 1) * k + i;
    put_cap(corner.get(), k, p->loop, &idx, &count);
    Far::TopologyDescriptor desc;
    desc.numVertices = k * kRings;
    desc.numFaces = static_cast<int>(Prism::faces(k, p->loop));
    desc.numVertsPerFace = p->counts.get();
    desc.vertIndicesPerFace = p->indices.get();
    Sdc::Options sdc;
    sdc.SetVtxBoundaryInterpolation(Sdc::Options::VTX_BOUNDARY_EDGE_AND_CORNER);
    Sdc::SchemeType scheme = p->loop ? Sdc::SCHEME_LOOP : Sdc::SCHEME_CATMARK;
    p->refiner.reset(Factory::Create(desc, Factory::Options(scheme, sdc)));
    return p->refiner != nullptr;
}

/* Every point of the refiner's last level, interpolated level by level. */
void last_level_points(const Prism &p, Buffer<Point3> *out)
{
    DoubleRefiner primvar(*p.refiner);
    Buffer<Point3> coarse(nullptr, 0);
    const Point3 *src = p.points.get();
    for (int level = 1; level <= p.refiner->GetMaxLevel(); ++level) {
        Buffer<Point3> fine(nullptr, size_t(p.refiner->GetLevel(level).GetNumVertices()));
        Point3 *dst = fine.get();
        if (!dst) throw std::bad_alloc();
        primvar.Interpolate(level, src, dst);
        coarse.swap(fine);
        src = coarse.get();
    }
    if (p.refiner->GetMaxLevel() == 0) {
        Buffer<Point3> copy(nullptr, size_t(p.k) * kRings);
        if (!copy.get()) throw std::bad_alloc();
        std::memcpy(copy.get(), p.points.get(), size_t(p.k) * kRings * sizeof(Point3));
        coarse.swap(copy);
    }
    out->swap(coarse);
}

/* The limit points of the last level's points (PrimvarRefiner::Limit). */
void limit_points(const Prism &p, const Point3 *src, Buffer<Point3> *out)
{
    Buffer<Point3> limits(nullptr, size_t(p.refiner->GetLevel(p.refiner->GetMaxLevel()).GetNumVertices()));
    Point3 *dst = limits.get();
    if (!dst) throw std::bad_alloc();
    DoubleRefiner(*p.refiner).Limit(src, dst);
    out->swap(limits);
}

/* The probe's index at the refiner's last level (a vertex's child keeps its parent's limit). */
Far::Index probe_index(const Prism &p)
{
    Far::Index v = p.probe;
    for (int level = 1; level <= p.refiner->GetMaxLevel(); ++level)
        v = p.refiner->GetLevel(level - 1).GetVertexChildVertex(v);
    return v;
}

double radius(const Point3 &p)
{
    return std::sqrt(p.x * p.x + p.y * p.y);
}

xyl_result limit_radius_factor(uint32_t k, double *factor)
{
    Prism p(static_cast<int>(k), false);
    if (!make_prism(&p)) return XYL_ERR_UNSUPPORTED;
    Refiner::UniformOptions uniform(1);
    uniform.fullTopologyInLastLevel = true; /* Limit() needs the last level's full topology */
    p.refiner->RefineUniform(uniform);
    Buffer<Point3> points(nullptr), limits(nullptr);
    last_level_points(p, &points);
    limit_points(p, points.get(), &limits);
    *factor = radius(limits.get()[probe_index(p)]);
    return XYL_OK;
}

xyl_result refined_radius_factor(uint32_t k, uint32_t levels, double *factor)
{
    Prism p(static_cast<int>(k), false);
    if (!make_prism(&p)) return XYL_ERR_UNSUPPORTED;
    if (levels) p.refiner->RefineUniform(Refiner::UniformOptions(static_cast<int>(levels)));
    Buffer<Point3> points(nullptr);
    last_level_points(p, &points);
    *factor = radius(points.get()[probe_index(p)]);
    return XYL_OK;
}

/* Mean radius of the limit surface over one band in the middle of the prism: the limit points
 * of the points of a 3-level refinement whose refined z lies in [4, 5). Those points sample the
 * band's parameter domain on a uniform lattice, and the surface is periodic in both directions
 * there (around the ring, and from band to band), so their mean is the periodic trapezoid rule:
 * exact to far below 1e-6 for these smooth periodic functions. */
xyl_result mean_limit_radius(uint32_t k, bool loop, double *mean)
{
    Prism p(static_cast<int>(k), loop);
    if (!make_prism(&p)) return XYL_ERR_UNSUPPORTED;
    Refiner::UniformOptions uniform(3);
    uniform.fullTopologyInLastLevel = true;
    p.refiner->RefineUniform(uniform);
    Buffer<Point3> points(nullptr), limits(nullptr);
    last_level_points(p, &points);
    limit_points(p, points.get(), &limits);
    const int n = p.refiner->GetLevel(3).GetNumVertices();
    const int mid = kRings / 2;
    double sum = 0.0;
    int count = 0;
    for (int v = 0; v < n; ++v) {
        const double z = points.get()[v].z;
        if (z < mid - 1e-9 || z >= mid + 1 - 1e-9) continue;
        sum += radius(limits.get()[v]);
        ++count;
    }
    if (count == 0) return XYL_ERR_UNSUPPORTED;
    *mean = sum / count;
    return XYL_OK;
}

} /* namespace */

/* The scheme is passed by address: a C caller may hand over a value outside the enum, and
 * loading that as an xyl_subdivision (passing it on by value) is undefined in C++;
 * read_scheme reads its bytes. */
static xyl_result subdivide_entry(const xyl__mesh_arrays *in, const xyl_subdivision *scheme,
                                  bool limit, const xyl_mesh_limits *limits,
                                  xyl__subdivide_path path, const xyl__creases *sharp,
                                  const xyl_allocator *alloc, xyl__mesh_arrays *out,
                                  xyl_diag *diag)
{
    if (!out)
        return xyl__fail(diag, XYL_ERR_INVALID_ARGUMENT, 0, 0, -1, "out must not be NULL");
    std::memset(out, 0, sizeof *out);
    if (!in) return xyl__fail(diag, XYL_ERR_INVALID_ARGUMENT, 0, 0, -1, "in must not be NULL");
    xyl_subdivision known;
    if (!read_scheme(scheme, &known)) return unknown_scheme(scheme, diag);
    /* Every array is owned by a Buffer or by out until the end, so an exception frees them. */
    xyl_result r;
    try {
        const Creases creases = {sharp ? sharp->pairs : nullptr, sharp ? sharp->count : 0};
        r = subdivide(in, known, limit, limits, path, creases, alloc, out, diag);
    } catch (const std::bad_alloc &) {
        r = xyl__fail(diag, XYL_ERR_OUT_OF_MEMORY, 0, 0, -1, "out of memory in OpenSubdiv");
    } catch (const std::length_error &) {
        r = xyl__fail(diag, XYL_ERR_OUT_OF_MEMORY, 0, 0, -1, "a size overflowed in OpenSubdiv");
    } catch (const std::exception &e) {
        r = xyl__fail(diag, XYL_ERR_UNSUPPORTED, 0, 0, -1, "OpenSubdiv failed: %s", e.what());
    } catch (...) {
        r = xyl__fail(diag, XYL_ERR_UNSUPPORTED, 0, 0, -1, "OpenSubdiv failed");
    }
    if (r == XYL_OK) {
        xyl__diag_ok(diag);
    } else {
        xyl__mesh_arrays_free(out, alloc); /* zeroes it too */
    }
    return r;
}

extern "C" xyl_result xyl__subdivide(const xyl__mesh_arrays *in, xyl_subdivision scheme,
                                     bool limit, const xyl_mesh_limits *limits,
                                     const xyl_allocator *alloc, xyl__mesh_arrays *out,
                                     xyl_diag *diag)
{
    return subdivide_entry(in, &scheme, limit, limits, XYL__SUBDIVIDE_ANY, nullptr, alloc, out,
                           diag);
}

extern "C" xyl_result xyl__subdivide_by(const xyl__mesh_arrays *in, xyl_subdivision scheme,
                                        bool limit, const xyl_mesh_limits *limits,
                                        xyl__subdivide_path path, const xyl_allocator *alloc,
                                        xyl__mesh_arrays *out, xyl_diag *diag)
{
    return subdivide_entry(in, &scheme, limit, limits, path, nullptr, alloc, out, diag);
}

extern "C" xyl_result xyl__subdivide_creased(const xyl__mesh_arrays *in,
                                             const xyl__creases *creases,
                                             xyl_subdivision scheme, bool limit,
                                             const xyl_mesh_limits *limits,
                                             xyl__subdivide_path path,
                                             const xyl_allocator *alloc, xyl__mesh_arrays *out,
                                             xyl_diag *diag)
{
    return subdivide_entry(in, &scheme, limit, limits, path, creases, alloc, out, diag);
}

extern "C" xyl_result xyl__subdivide_limit_radius_factor(uint32_t k, double *factor)
{
    if (!factor || k < 3 || k > 32) return XYL_ERR_INVALID_ARGUMENT;
    try {
        return limit_radius_factor(k, factor);
    } catch (const std::bad_alloc &) {
        return XYL_ERR_OUT_OF_MEMORY;
    } catch (...) {
        return XYL_ERR_UNSUPPORTED;
    }
}

extern "C" xyl_result xyl__subdivide_refined_radius_factor(uint32_t k, uint32_t levels,
                                                          double *factor)
{
    if (!factor || k < 3 || k > 32 || levels > 6) return XYL_ERR_INVALID_ARGUMENT;
    try {
        return refined_radius_factor(k, levels, factor);
    } catch (const std::bad_alloc &) {
        return XYL_ERR_OUT_OF_MEMORY;
    } catch (...) {
        return XYL_ERR_UNSUPPORTED;
    }
}

extern "C" xyl_result xyl__subdivide_mean_limit_radius(xyl_subdivision scheme, uint32_t k,
                                                       double *mean)
{
    if (!mean || k < 3 || k > 32 ||
        (scheme != XYL_SUBDIVIDE_CATMARK && scheme != XYL_SUBDIVIDE_LOOP))
        return XYL_ERR_INVALID_ARGUMENT;
    try {
        return mean_limit_radius(k, scheme == XYL_SUBDIVIDE_LOOP, mean);
    } catch (const std::bad_alloc &) {
        return XYL_ERR_OUT_OF_MEMORY;
    } catch (...) {
        return XYL_ERR_UNSUPPORTED;
    }
}

extern "C" xyl_result xyl_mesh_subdivide(const xyl_mesh *mesh, const xyl_subdivide_desc *desc,
                                         xyl_mesh **out, xyl_diag *diag)
{
    if (!mesh || !out)
        return xyl__fail(diag, XYL_ERR_INVALID_ARGUMENT, 0, 0, -1,
                         "mesh and out must not be NULL");
    xyl_subdivide_desc defaults;
    std::memset(&defaults, 0, sizeof defaults);
    const xyl_subdivide_desc *d = desc ? desc : &defaults;
    xyl_subdivision scheme;
    if (!read_scheme(&d->scheme, &scheme)) return unknown_scheme(&d->scheme, diag);
    /* A read-only view: xyl__subdivide never writes through in. */
    xyl__mesh_arrays view;
    std::memset(&view, 0, sizeof view);
    view.positions = const_cast<xyl_vec3 *>(mesh->positions);
    view.normals = const_cast<xyl_vec3 *>(mesh->normals);
    view.uvs = const_cast<float *>(mesh->uvs);
    view.branch_ids = const_cast<uint32_t *>(mesh->branch_ids);
    view.vertex_count = mesh->vertex_count;
    view.quads = const_cast<uint32_t *>(mesh->quads);
    view.quad_count = mesh->quad_count;
    view.triangles = const_cast<uint32_t *>(mesh->triangles);
    view.triangle_count = mesh->triangle_count;
    view.face_branches = const_cast<uint32_t *>(mesh->face_branches);
    view.uv_wraps = const_cast<uint8_t *>(mesh->uv_wraps);
    xyl__mesh_arrays refined;
    xyl_result r = xyl__subdivide(&view, scheme, !d->keep_control_points, &d->limits, &d->alloc,
                                  &refined, diag);
    if (r) return r;
    std::memcpy(refined.origin, mesh->origin, sizeof refined.origin);
    return xyl__mesh_adopt(&refined, &d->alloc, out, diag); /* smooth normals unless copied */
}
