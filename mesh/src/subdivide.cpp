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

std::unique_ptr<Refiner> create_refiner(Sdc::SchemeType type, int vertices, const Control &c)
{
    Far::TopologyDescriptor desc;
    desc.numVertices = vertices;
    desc.numFaces = c.faces;
    desc.numVertsPerFace = c.counts.get();
    desc.vertIndicesPerFace = c.indices.get();
    Sdc::Options sdc;
    /* Boundaries (none on a closed stem mesh) stay put: sharp edges and corners. */
    sdc.SetVtxBoundaryInterpolation(Sdc::Options::VTX_BOUNDARY_EDGE_AND_CORNER);
    return std::unique_ptr<Refiner>(Factory::Create(desc, Factory::Options(type, sdc)));
}

/* The branch of the vertex an edge gives birth to: the branch of its faces when they agree,
 * else (a seam between branches) its end vertices' branch when they agree, else the smallest
 * of its faces' branches. */
uint32_t edge_branch(const Far::TopologyLevel &base, Far::Index e, const uint32_t *vertex_branch,
                     const uint32_t *face_branch)
{
    Far::ConstIndexArray faces = base.GetEdgeFaces(e);
    bool agree = true;
    uint32_t lowest = UINT32_MAX;
    for (int i = 0; i < faces.size(); ++i) {
        uint32_t b = face_branch[faces[i]];
        agree = agree && b == face_branch[faces[0]];
        lowest = b < lowest ? b : lowest;
    }
    if (faces.size() > 0 && agree) return lowest;
    Far::ConstIndexArray ends = base.GetEdgeVertices(e);
    uint32_t b0 = vertex_branch ? vertex_branch[ends[0]] : 0;
    uint32_t b1 = vertex_branch ? vertex_branch[ends[1]] : 0;
    if (b0 == b1 || faces.size() == 0) return b0 < b1 ? b0 : b1;
    return lowest;
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

/* Sum of the area-weighted normals of a level-1 vertex's faces (twice the area for triangles,
 * the diagonals' cross product for quads): the orientation reference for its limit normal, and
 * the normal where the limit tangents are degenerate. */
Point3 face_normal_sum(const Far::TopologyLevel &fine, Far::Index v, const Point3 *p)
{
    Point3 sum = {0.0, 0.0, 0.0};
    Far::ConstIndexArray faces = fine.GetVertexFaces(v);
    for (int i = 0; i < faces.size(); ++i) {
        Far::ConstIndexArray fv = fine.GetFaceVertices(faces[i]);
        Point3 n = fv.size() == 4 ? cross(sub(p[fv[2]], p[fv[0]]), sub(p[fv[3]], p[fv[1]]))
                                  : cross(sub(p[fv[1]], p[fv[0]]), sub(p[fv[2]], p[fv[0]]));
        sum.AddWithWeight(n, 1.0);
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
    for (size_t v = 0; v < n1; ++v) {
        Point3 n = cross(t1[v], t2[v]);
        Point3 ref = face_normal_sum(fine, static_cast<Far::Index>(v), lp);
        double scale = std::sqrt(dot(t1[v], t1[v]) * dot(t2[v], t2[v]));
        if (!(std::sqrt(dot(n, n)) > 1e-9 * scale)) n = Point3{0.0, 0.0, 0.0};
        if (dot(n, ref) < 0.0) n = Point3{-n.x, -n.y, -n.z};
        normals[v] = unit_or(n, ref);
    }
    std::memcpy(pd, lp, n1 * sizeof *pd);
    return true;
}

/* What a level-1 vertex is born of: a base vertex, edge or face (the index of which). */
struct Origin {
    enum Kind : uint8_t { VERTEX, EDGE, FACE } kind;
    int index;
};

void find_origins(const Far::TopologyLevel &base, bool face_points, Origin *out)
{
    for (int v = 0; v < base.GetNumVertices(); ++v)
        out[base.GetVertexChildVertex(v)] = Origin{Origin::VERTEX, v};
    for (int e = 0; e < base.GetNumEdges(); ++e)
        out[base.GetEdgeChildVertex(e)] = Origin{Origin::EDGE, e};
    if (!face_points) return;
    for (int f = 0; f < base.GetNumFaces(); ++f)
        out[base.GetFaceChildVertex(f)] = Origin{Origin::FACE, f};
}

/* Base face f in its own UV frame (its corners with their wraps): the UV it gives each kind of
 * level-1 vertex of its child faces, linear as OpenSubdiv's varying rules (a vertex keeps its UV,
 * an edge point averages its ends, a face point the face's corners), and its u span. Faces are
 * quads or triangles. */
struct FaceFrame {
    Far::ConstIndexArray fv, fe;
    Point2 corner[4], edge[4], centre;
    double span;

    FaceFrame(const Far::TopologyLevel &base, int f, uint8_t wraps, const float *uvs)
        : fv(base.GetFaceVertices(f)), fe(base.GetFaceEdges(f)), centre{0.0, 0.0}
    {
        const int n = fv.size();
        double lo = INFINITY, hi = -INFINITY;
        for (int c = 0; c < n; ++c) {
            corner[c] = Point2{uvs ? uvs[2 * fv[c]] : 0.0, uvs ? uvs[2 * fv[c] + 1] : 0.0};
            if (wraps >> c & 1u) corner[c].u += 1.0;
            lo = corner[c].u < lo ? corner[c].u : lo;
            hi = corner[c].u > hi ? corner[c].u : hi;
        }
        span = hi - lo;
        const double w = 1.0 / n;
        for (int c = 0; c < n; ++c) centre.AddWithWeight(corner[c], w);
        for (int e = 0; e < n; ++e) { /* its ends' corners, in corner order */
            Far::ConstIndexArray ends = base.GetEdgeVertices(fe[e]);
            edge[e] = Point2{0.0, 0.0};
            for (int c = 0; c < n; ++c)
                if (fv[c] == ends[0] || fv[c] == ends[1]) edge[e].AddWithWeight(corner[c], 0.5);
        }
    }

    Point2 at(const Origin &o) const
    {
        const int n = fv.size();
        if (o.kind == Origin::FACE) return centre;
        const Far::ConstIndexArray &of = o.kind == Origin::VERTEX ? fv : fe;
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
bool interpolate_uvs(const Refiner &r, const xyl__mesh_arrays *in, const Control &control,
                     bool face_points, const xyl_allocator *alloc, Refined *out)
{
    const Far::TopologyLevel &base = r.GetLevel(0), &fine = r.GetLevel(1);
    const size_t n1 = static_cast<size_t>(fine.GetNumVertices());
    Buffer<Origin> origin(alloc, n1);
    Buffer<Point2> uv(alloc, n1);
    Buffer<double> narrowest(alloc, n1); /* the span of the parent face uv[] came from */
    Buffer<uint8_t> seen(alloc, n1);
    if (!origin.get() || !uv.get() || !narrowest.get() || !seen.get()) return false;
    find_origins(base, face_points, origin.get());
    const uint8_t *parent_wraps = control.wraps.get();
    for (int f = 0; f < base.GetNumFaces(); ++f) {
        const FaceFrame frame(base, f, parent_wraps[f], in->uvs);
        Far::ConstIndexArray kids = base.GetFaceChildFaces(f);
        for (int i = 0; i < kids.size(); ++i) {
            Far::ConstIndexArray fv = fine.GetFaceVertices(kids[i]);
            for (int j = 0; j < fv.size(); ++j) {
                const Point2 c = frame.at(origin.get()[fv[j]]);
                Point2 &own = uv.get()[fv[j]];
                double &best = narrowest.get()[fv[j]];
                bool take = !seen.get()[fv[j]] || frame.span < best ||
                            (frame.span == best && c.u < own.u);
                if (take) own = c, best = frame.span;
                seen.get()[fv[j]] = 1;
            }
        }
    }
    for (int f = 0; f < base.GetNumFaces(); ++f) {
        const FaceFrame frame(base, f, parent_wraps[f], in->uvs);
        Far::ConstIndexArray kids = base.GetFaceChildFaces(f);
        for (int i = 0; i < kids.size(); ++i) {
            Far::ConstIndexArray fv = fine.GetFaceVertices(kids[i]);
            uint8_t bits = 0;
            for (int j = 0; j < fv.size(); ++j)
                if (frame.at(origin.get()[fv[j]]).u - uv.get()[fv[j]].u >= 0.5)
                    bits = static_cast<uint8_t>(bits | 1u << j);
            out->wraps.get()[kids[i]] = bits;
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

xyl_result refine(const xyl__mesh_arrays *in, xyl_subdivision scheme, bool limit,
                  const Limits &lim, const xyl_allocator *alloc, xyl__mesh_arrays *out,
                  xyl_diag *diag)
{
    const bool loop = scheme == XYL_SUBDIVIDE_LOOP;
    const uint64_t far_faces = loop ? 2u * uint64_t(in->quad_count) + in->triangle_count
                                    : uint64_t(face_count(in));
    const uint64_t corners = 4u * uint64_t(in->quad_count) + 3u * uint64_t(in->triangle_count) +
                             (loop ? 2u * uint64_t(in->quad_count) : 0u);
    if (in->vertex_count > kIntMax || far_faces > kIntMax || corners > kIntMax)
        return xyl__fail(diag, XYL_ERR_UNSUPPORTED, 0, 0, -1,
                         "the mesh is too large for OpenSubdiv's int indices");
    Control control(alloc, static_cast<size_t>(far_faces), static_cast<size_t>(corners));
    if (!control.ok())
        return xyl__fail(diag, XYL_ERR_OUT_OF_MEMORY, 0, 0, -1, "out of memory for the topology");
    fill_control(in, loop, &control);
    std::unique_ptr<Refiner> r = create_refiner(loop ? Sdc::SCHEME_LOOP : Sdc::SCHEME_CATMARK,
                                                static_cast<int>(in->vertex_count), control);
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
    if (!fine.ok(limit) || !interpolate_positions(*r, in, alloc, &fine) ||
        !interpolate_uvs(*r, in, control, !loop, alloc, &fine))
        return xyl__fail(diag, XYL_ERR_OUT_OF_MEMORY, 0, 0, -1,
                         "out of memory for the refined mesh");
    const uint32_t *parent_branch = control.branches.get();
    uint32_t *child_branch = fine.face_branches.get();
    DoubleRefiner(*r).InterpolateFaceUniform(1, parent_branch, child_branch);
    assign_vertex_branches(*r, in, parent_branch, !loop, fine.branch_ids.get());
    copy_faces(*r, corners1, fine.faces.get());

    /* The other face array is empty but, as in xyl_mesh_create, not NULL. */
    Buffer<uint32_t> empty(alloc, 0);
    if (!empty.get())
        return xyl__fail(diag, XYL_ERR_OUT_OF_MEMORY, 0, 0, -1, "out of memory for the mesh");
    std::memset(out, 0, sizeof *out);
    out->vertex_count = static_cast<size_t>(v1);
    out->positions = fine.positions.release();
    out->normals = fine.normals.release();
    out->uvs = fine.uvs.release();
    out->branch_ids = fine.branch_ids.release();
    out->face_branches = fine.face_branches.release();
    out->uv_wraps = fine.wraps.release();
    if (loop) {
        out->triangle_count = static_cast<size_t>(f1);
        out->triangles = fine.faces.release();
        out->quads = empty.release();
    } else {
        out->quad_count = static_cast<size_t>(f1);
        out->quads = fine.faces.release();
        out->triangles = empty.release();
    }
    return XYL_OK;
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
                     const xyl_mesh_limits *limits, const xyl_allocator *alloc,
                     xyl__mesh_arrays *out, xyl_diag *diag)
{
    xyl_result r = validate_input(in, diag);
    if (r) return r;
    const Limits lim = effective_limits(limits);
    if (scheme == XYL_SUBDIVIDE_NONE || face_count(in) == 0) {
        r = check_limits(in->vertex_count, face_count(in), lim, diag);
        if (r) return r;
        return copy_mesh(in, scheme == XYL_SUBDIVIDE_NONE, alloc, out, diag);
    }
    return refine(in, scheme, limit, lim, alloc, out, diag);
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

extern "C" xyl_result xyl__subdivide(const xyl__mesh_arrays *in, xyl_subdivision scheme,
                                     bool limit, const xyl_mesh_limits *limits,
                                     const xyl_allocator *alloc, xyl__mesh_arrays *out,
                                     xyl_diag *diag)
{
    if (!out)
        return xyl__fail(diag, XYL_ERR_INVALID_ARGUMENT, 0, 0, -1, "out must not be NULL");
    std::memset(out, 0, sizeof *out);
    if (!in) return xyl__fail(diag, XYL_ERR_INVALID_ARGUMENT, 0, 0, -1, "in must not be NULL");
    xyl_subdivision known;
    if (!read_scheme(&scheme, &known)) return unknown_scheme(&scheme, diag);
    /* Every array is owned by a Buffer or by out until the end, so an exception frees them. */
    xyl_result r;
    try {
        r = subdivide(in, known, limit, limits, alloc, out, diag);
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
    return xyl__mesh_adopt(&refined, &d->alloc, out, diag); /* smooth normals unless copied */
}
