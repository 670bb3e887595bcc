// tinygltf is built here (header-only upstream) without image support: xylem needs geometry only.
#define TINYGLTF_IMPLEMENTATION
#define TINYGLTF_NO_STB_IMAGE
#define TINYGLTF_NO_STB_IMAGE_WRITE
#define TINYGLTF_NO_EXTERNAL_IMAGE
#include <tiny_gltf.h>

#include "glb_read.h"

#include <cmath>
#include <cstdlib>
#include <cstdio>
#include <cstring>
#include <new>
#include <string>
#include <vector>

namespace {

struct parts {
    std::vector<xyl_vec3> positions, normals;
    std::vector<uint32_t> triangles, quads;
    bool with_normals = true;
};

xyl_result fail(xyl_diag *d, xyl_result code, const std::string &msg)
{
    if (d) {
        d->code = code;
        std::snprintf(d->message, sizeof d->message, "%s", msg.c_str());
        d->line = d->column = 0;
        d->index = -1;
    }
    return code;
}

// Bytes of element i of an accessor, or nullptr when the accessor, view or buffer cannot hold it.
const unsigned char *element(const tinygltf::Model &m, const tinygltf::Accessor &a, size_t i,
                             size_t elem_bytes)
{
    if (a.bufferView < 0 || size_t(a.bufferView) >= m.bufferViews.size() || a.sparse.isSparse)
        return nullptr;
    const tinygltf::BufferView &v = m.bufferViews[size_t(a.bufferView)];
    if (v.buffer < 0 || size_t(v.buffer) >= m.buffers.size()) return nullptr;
    const std::vector<unsigned char> &data = m.buffers[size_t(v.buffer)].data;
    size_t stride = v.byteStride ? v.byteStride : elem_bytes;
    size_t off = v.byteOffset + a.byteOffset;
    if (stride < elem_bytes || i >= a.count || v.byteOffset > data.size() ||
        v.byteLength > data.size() - v.byteOffset || a.byteOffset > v.byteLength)
        return nullptr;
    size_t end = a.byteOffset + i * stride + elem_bytes; // within the view
    if (i > (SIZE_MAX - elem_bytes - a.byteOffset) / stride || end > v.byteLength) return nullptr;
    return data.data() + off + i * stride;
}

bool read_vec3s(const tinygltf::Model &m, int index, std::vector<xyl_vec3> &out)
{
    if (index < 0 || size_t(index) >= m.accessors.size()) return false;
    const tinygltf::Accessor &a = m.accessors[size_t(index)];
    if (a.type != TINYGLTF_TYPE_VEC3 || a.componentType != TINYGLTF_COMPONENT_TYPE_FLOAT)
        return false;
    for (size_t i = 0; i < a.count; ++i) {
        const unsigned char *p = element(m, a, i, 12);
        if (!p) return false;
        xyl_vec3 v;
        std::memcpy(&v, p, 12);
        out.push_back(v);
    }
    return true;
}

bool read_indices(const tinygltf::Model &m, int index, size_t base, size_t nverts,
                  std::vector<uint32_t> &out)
{
    if (index < 0) { // non-indexed: consecutive triples
        for (size_t i = 0; i + 2 < nverts; i += 3)
            for (size_t k = 0; k < 3; ++k) out.push_back(uint32_t(base + i + k));
        return nverts % 3 == 0;
    }
    if (size_t(index) >= m.accessors.size()) return false;
    const tinygltf::Accessor &a = m.accessors[size_t(index)];
    int ct = a.componentType;
    size_t bytes = ct == TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE    ? 1
                   : ct == TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT ? 2
                   : ct == TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT   ? 4 : 0;
    if (!bytes || a.type != TINYGLTF_TYPE_SCALAR || a.count % 3) return false;
    for (size_t i = 0; i < a.count; ++i) {
        const unsigned char *p = element(m, a, i, bytes);
        if (!p) return false;
        uint32_t v = 0;
        if (bytes == 1) v = p[0];
        else if (bytes == 2) { uint16_t s; std::memcpy(&s, p, 2); v = s; }
        else std::memcpy(&v, p, 4);
        if (v >= nverts) return false;
        out.push_back(uint32_t(base + v));
    }
    return true;
}

xyl_result read_primitive(const tinygltf::Model &m, const tinygltf::Primitive &pr, parts &out,
                          xyl_diag *d)
{
    if (pr.mode != TINYGLTF_MODE_TRIANGLES) return XYL_OK; // points and lines are not surfaces
    auto pos = pr.attributes.find("POSITION"), nrm = pr.attributes.find("NORMAL");
    size_t base = out.positions.size();
    if (pos == pr.attributes.end() || !read_vec3s(m, pos->second, out.positions))
        return fail(d, XYL_ERR_PARSE, "a primitive's POSITION is missing or not a float VEC3 in range");
    size_t n = out.positions.size() - base;
    bool has_normals = nrm != pr.attributes.end();
    if (base == 0) out.with_normals = has_normals;
    if (has_normals != out.with_normals)
        return fail(d, XYL_ERR_PARSE, "some primitives have NORMAL and others do not");
    if (has_normals && (!read_vec3s(m, nrm->second, out.normals) || out.normals.size() != out.positions.size()))
        return fail(d, XYL_ERR_PARSE, "a primitive's NORMAL is not a float VEC3 per vertex");
    if (out.positions.size() > UINT32_MAX)
        return fail(d, XYL_ERR_LIMIT_EXCEEDED, "more than 2^32 vertices");
    if (!read_indices(m, pr.indices, base, n, out.triangles))
        return fail(d, XYL_ERR_PARSE, "a primitive's indices are not unsigned, in range and a multiple of 3");
    return XYL_OK;
}

// The GLB writer splits quad (a, b, c, d) into (a, b, c), (a, c, d): join such pairs again.
void rejoin_quads(parts &p)
{
    std::vector<uint32_t> tris;
    const std::vector<uint32_t> &t = p.triangles;
    size_t n = t.size() / 3, i = 0;
    for (; i + 1 < n; i += 2) {
        const uint32_t *x = &t[3 * i], *y = &t[3 * i + 3];
        if (x[0] != y[0] || x[2] != y[1] || y[2] == x[1]) break;
        p.quads.insert(p.quads.end(), {x[0], x[1], x[2], y[2]});
    }
    tris.assign(t.begin() + std::ptrdiff_t(3 * i), t.end());
    p.triangles.swap(tris);
}

xyl_result build(const tinygltf::Model &m, xyl_mesh **out, xyl_diag *d)
{
    parts p;
    bool ours = m.asset.generator == "xylem";
    for (const tinygltf::Mesh &mesh : m.meshes) {
        if (ours && mesh.name == "leaves") continue; // leaf quads: foliage, not a stem surface
        for (const tinygltf::Primitive &pr : mesh.primitives) {
            xyl_result r = read_primitive(m, pr, p, d);
            if (r != XYL_OK) return r;
        }
    }
    if (p.triangles.empty()) return fail(d, XYL_ERR_PARSE, "the file has no triangles");
    if (ours) rejoin_quads(p);
    xyl_mesh_desc md = {};
    md.positions = p.positions.data();
    md.normals = p.with_normals ? p.normals.data() : nullptr;
    md.vertex_count = p.positions.size();
    md.quads = p.quads.data();
    md.quad_count = p.quads.size() / 4;
    md.triangles = p.triangles.data();
    md.triangle_count = p.triangles.size() / 3;
    // xylem's writers put the mesh's origin in its node's translation (docs/mesh-export.md)
    for (const tinygltf::Node &n : m.nodes)
        if (ours && n.mesh >= 0 && n.translation.size() == 3 &&
            m.meshes[size_t(n.mesh)].name != "leaves")
            for (int k = 0; k < 3; ++k) md.origin[k] = n.translation[size_t(k)];
    xyl_result r = xyl_mesh_create(&md, out, d);
    // a face the file gets wrong (an index repeated in a triangle) is bad input, not a bad call
    if (r == XYL_ERR_INVALID_ARGUMENT)
        return fail(d, XYL_ERR_PARSE, std::string("the mesh is not valid: ") + (d ? d->message : ""));
    return r;
}

// Embedded images are kept as bytes and not decoded: the readers need geometry only.
bool skip_image(tinygltf::Image *, const int, std::string *, std::string *, int, int,
                const unsigned char *, int, void *)
{
    return true;
}

bool load(const unsigned char *data, size_t size, tinygltf::Model &model, xyl_diag *d,
          xyl_result *r)
{
    tinygltf::TinyGLTF loader;
    loader.SetImageLoader(skip_image, nullptr);
    std::string err, warn;
    if (loader.LoadBinaryFromMemory(&model, &err, &warn, data, unsigned(size), "")) return true;
    *r = fail(d, XYL_ERR_PARSE, err.empty() ? "not a glTF binary" : err);
    return false;
}

// ---- leaves (xyl_foliage_write_glb_*) ----

template <typename T> T *copy_out(const std::vector<T> &v)
{
    T *p = static_cast<T *>(std::malloc(v.empty() ? 1 : v.size() * sizeof(T)));
    if (!p) throw std::bad_alloc();
    if (!v.empty()) std::memcpy(p, v.data(), v.size() * sizeof(T));
    return p;
}

bool count_of(const tinygltf::Value &o, const char *key, uint64_t max, uint64_t *out)
{
    const tinygltf::Value &v = o.IsObject() ? o.Get(key) : o;
    if (!v.IsNumber()) return false;
    double x = v.GetNumberAsDouble();
    if (!(x >= 0.0) || x > double(max) || x != std::floor(x)) return false;
    *out = uint64_t(x);
    return true;
}

bool read_sector(const tinygltf::Value &o, xyl_sample_leaf_sector *s)
{
    uint64_t base, n, m;
    if (!o.IsObject() || !count_of(o, "base", UINT32_MAX, &base) || !count_of(o, "original_count", UINT32_MAX, &n) ||
        !count_of(o, "merged_count", UINT32_MAX, &m))
        return false;
    s->base = uint32_t(base);
    s->original_count = uint32_t(n);
    s->merged_count = uint32_t(m);
    const tinygltf::Value &lods = o.Get("lods");
    if (!lods.IsArray() || lods.ArrayLen() != m + 1) return false;
    std::vector<xyl_sample_leaf_lod> rows;
    for (size_t i = 0; i < lods.ArrayLen(); ++i) {
        const tinygltf::Value &r = lods.Get(int(i));
        uint64_t a, b, c;
        if (r.ArrayLen() != 4 || !count_of(r.Get(0), "", UINT32_MAX, &a) ||
            !count_of(r.Get(1), "", UINT32_MAX, &b) || !count_of(r.Get(2), "", UINT32_MAX, &c) ||
            !r.Get(3).IsNumber())
            return false;
        rows.push_back({uint32_t(a), uint32_t(b), uint32_t(c), float(r.Get(3).GetNumberAsDouble())});
    }
    s->lod_count = rows.size();
    s->lods = copy_out(rows);
    return true;
}

xyl_result read_extras(const tinygltf::Value &extras, xyl_sample_glb_leaves *out, xyl_diag *d)
{
    const tinygltf::Value &x = extras.IsObject() ? extras.Get("xylem_foliage") : extras;
    uint64_t leaves, originals, version;
    if (!x.IsObject() || !count_of(x, "version", 1, &version) || version != 1 ||
        !count_of(x, "leaf_count", UINT32_MAX, &leaves) ||
        !count_of(x, "original_count", UINT32_MAX, &originals) || !x.Get("sectors").IsArray())
        return fail(d, XYL_ERR_PARSE, "the leaves node has no extras.xylem_foliage of version 1");
    out->extras_leaf_count = size_t(leaves);
    out->extras_original_count = size_t(originals);
    const tinygltf::Value &sectors = x.Get("sectors");
    size_t n = sectors.ArrayLen();
    out->sectors = static_cast<xyl_sample_leaf_sector *>(std::calloc(n ? n : 1, sizeof *out->sectors));
    if (!out->sectors) throw std::bad_alloc();
    for (size_t k = 0; k < n; ++k) {
        if (!read_sector(sectors.Get(int(k)), &out->sectors[k]))
            return fail(d, XYL_ERR_PARSE, "sector " + std::to_string(k) + " of the extras is malformed");
        out->sector_count = uint32_t(k + 1);
    }
    return XYL_OK;
}

bool read_vec2s(const tinygltf::Model &m, int index, std::vector<float> &out)
{
    if (index < 0 || size_t(index) >= m.accessors.size()) return false;
    const tinygltf::Accessor &a = m.accessors[size_t(index)];
    if (a.type != TINYGLTF_TYPE_VEC2 || a.componentType != TINYGLTF_COMPONENT_TYPE_FLOAT)
        return false;
    for (size_t i = 0; i < a.count; ++i) {
        const unsigned char *p = element(m, a, i, 8);
        if (!p) return false;
        float v[2];
        std::memcpy(v, p, 8);
        out.insert(out.end(), {v[0], v[1]});
    }
    return true;
}

xyl_result read_leaf_mesh(const tinygltf::Model &m, const tinygltf::Mesh &mesh,
                          xyl_sample_glb_leaves *out, xyl_diag *d)
{
    if (mesh.primitives.size() != 1) return fail(d, XYL_ERR_PARSE, "the leaves mesh has not one primitive");
    const tinygltf::Primitive &pr = mesh.primitives[0];
    auto at = [&](const char *k) {
        auto it = pr.attributes.find(k);
        return it == pr.attributes.end() ? -1 : it->second;
    };
    std::vector<xyl_vec3> pos, nrm;
    std::vector<float> uv;
    std::vector<uint32_t> idx;
    if (pr.mode != TINYGLTF_MODE_TRIANGLES || !read_vec3s(m, at("POSITION"), pos) ||
        !read_vec3s(m, at("NORMAL"), nrm) || !read_vec2s(m, at("TEXCOORD_0"), uv) ||
        pos.size() % 4 || nrm.size() != pos.size() || uv.size() != 2 * pos.size() ||
        !read_indices(m, pr.indices, 0, pos.size(), idx) || idx.size() != pos.size() / 4 * 6)
        return fail(d, XYL_ERR_PARSE, "the leaves primitive is not 4 vertices and 6 indices a leaf");
    out->leaf_count = pos.size() / 4;
    out->positions = copy_out(pos);
    out->normals = copy_out(nrm);
    out->uvs = copy_out(uv);
    out->indices = copy_out(idx);
    if (pr.material < 0 || size_t(pr.material) >= m.materials.size())
        return fail(d, XYL_ERR_PARSE, "the leaves primitive has no material");
    const tinygltf::Material &mat = m.materials[size_t(pr.material)];
    out->masked = mat.alphaMode == "MASK";
    out->double_sided = mat.doubleSided;
    out->alpha_cutoff = mat.alphaCutoff;
    int tex = mat.pbrMetallicRoughness.baseColorTexture.index;
    if (tex >= 0 && size_t(tex) < m.textures.size()) {
        int src = m.textures[size_t(tex)].source;
        if (src < 0 || size_t(src) >= m.images.size() || m.images[size_t(src)].bufferView < 0 ||
            size_t(m.images[size_t(src)].bufferView) >= m.bufferViews.size())
            return fail(d, XYL_ERR_PARSE, "the leaves' texture has no embedded image");
        out->texture_bytes = m.bufferViews[size_t(m.images[size_t(src)].bufferView)].byteLength;
    }
    return XYL_OK;
}

xyl_result build_leaves(const tinygltf::Model &m, xyl_sample_glb_leaves *out, xyl_diag *d)
{
    const tinygltf::Node *leaves = nullptr;
    for (const tinygltf::Node &n : m.nodes)
        if (n.name == "leaves") leaves = &n;
    if (!leaves) return fail(d, XYL_ERR_PARSE, "the file has no node \"leaves\"");
    for (const tinygltf::Mesh &mesh : m.meshes)
        if (mesh.name == "stems")
            for (const tinygltf::Primitive &pr : mesh.primitives) {
                auto it = pr.attributes.find("POSITION");
                if (it != pr.attributes.end() && it->second >= 0 && size_t(it->second) < m.accessors.size())
                    out->stem_vertex_count += m.accessors[size_t(it->second)].count;
            }
    xyl_result r = read_extras(leaves->extras, out, d);
    if (r == XYL_OK && leaves->mesh >= 0) {
        if (size_t(leaves->mesh) >= m.meshes.size())
            return fail(d, XYL_ERR_PARSE, "the leaves node's mesh is not in the file");
        r = read_leaf_mesh(m, m.meshes[size_t(leaves->mesh)], out, d);
    }
    return r;
}

} // namespace

extern "C" void xyl_sample_glb_leaves_free(xyl_sample_glb_leaves *l)
{
    if (!l) return;
    std::free(l->positions);
    std::free(l->normals);
    std::free(l->uvs);
    std::free(l->indices);
    for (uint32_t k = 0; l->sectors && k < l->sector_count; ++k) std::free(l->sectors[k].lods);
    std::free(l->sectors);
    std::memset(l, 0, sizeof *l);
}

extern "C" xyl_result xyl_sample_read_glb_leaves(const unsigned char *data, size_t size,
                                                 xyl_sample_glb_leaves *out, xyl_diag *diag)
{
    if (!data || !out) return fail(diag, XYL_ERR_INVALID_ARGUMENT, "data and out are required");
    std::memset(out, 0, sizeof *out);
    if (size > 0xffffffffu) return fail(diag, XYL_ERR_LIMIT_EXCEEDED, "a GLB is at most 4 GiB");
    xyl_result r = XYL_OK;
    try {
        tinygltf::Model model;
        if (load(data, size, model, diag, &r)) r = build_leaves(model, out, diag);
    } catch (const std::bad_alloc &) {
        r = fail(diag, XYL_ERR_OUT_OF_MEMORY, "out of memory reading the GLB");
    } catch (const std::exception &e) {
        r = fail(diag, XYL_ERR_PARSE, std::string("malformed GLB: ") + e.what());
    } catch (...) {
        r = fail(diag, XYL_ERR_PARSE, "malformed GLB");
    }
    if (r != XYL_OK) xyl_sample_glb_leaves_free(out);
    return r;
}

extern "C" xyl_result xyl_sample_read_glb(const unsigned char *data, size_t size, xyl_mesh **out,
                                          xyl_diag *diag)
{
    if (!data || !out) return fail(diag, XYL_ERR_INVALID_ARGUMENT, "data and out are required");
    if (size > 0xffffffffu) return fail(diag, XYL_ERR_LIMIT_EXCEEDED, "a GLB is at most 4 GiB");
    try {
        tinygltf::Model model;
        xyl_result r = XYL_OK;
        if (!load(data, size, model, diag, &r)) return r;
        return build(model, out, diag);
    } catch (const std::bad_alloc &) {
        return fail(diag, XYL_ERR_OUT_OF_MEMORY, "out of memory reading the GLB");
    } catch (const std::exception &e) {
        return fail(diag, XYL_ERR_PARSE, std::string("malformed GLB: ") + e.what());
    } catch (...) {
        return fail(diag, XYL_ERR_PARSE, "malformed GLB");
    }
}
