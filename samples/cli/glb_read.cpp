// tinygltf is built here (header-only upstream) without image support: xylem needs geometry only.
#define TINYGLTF_IMPLEMENTATION
#define TINYGLTF_NO_STB_IMAGE
#define TINYGLTF_NO_STB_IMAGE_WRITE
#define TINYGLTF_NO_EXTERNAL_IMAGE
#include <tiny_gltf.h>

#include "glb_read.h"

#include <cmath>
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
    for (const tinygltf::Mesh &mesh : m.meshes)
        for (const tinygltf::Primitive &pr : mesh.primitives) {
            xyl_result r = read_primitive(m, pr, p, d);
            if (r != XYL_OK) return r;
        }
    if (p.triangles.empty()) return fail(d, XYL_ERR_PARSE, "the file has no triangles");
    if (m.asset.generator == "xylem") rejoin_quads(p);
    xyl_mesh_desc md = {};
    md.positions = p.positions.data();
    md.normals = p.with_normals ? p.normals.data() : nullptr;
    md.vertex_count = p.positions.size();
    md.quads = p.quads.data();
    md.quad_count = p.quads.size() / 4;
    md.triangles = p.triangles.data();
    md.triangle_count = p.triangles.size() / 3;
    return xyl_mesh_create(&md, out, d);
}

} // namespace

extern "C" xyl_result xyl_sample_read_glb(const unsigned char *data, size_t size, xyl_mesh **out,
                                          xyl_diag *diag)
{
    if (!data || !out) return fail(diag, XYL_ERR_INVALID_ARGUMENT, "data and out are required");
    if (size > 0xffffffffu) return fail(diag, XYL_ERR_LIMIT_EXCEEDED, "a GLB is at most 4 GiB");
    try {
        tinygltf::TinyGLTF loader;
        tinygltf::Model model;
        std::string err, warn;
        if (!loader.LoadBinaryFromMemory(&model, &err, &warn, data, unsigned(size), ""))
            return fail(diag, XYL_ERR_PARSE, err.empty() ? "not a glTF binary" : err);
        return build(model, out, diag);
    } catch (const std::bad_alloc &) {
        return fail(diag, XYL_ERR_OUT_OF_MEMORY, "out of memory reading the GLB");
    } catch (const std::exception &e) {
        return fail(diag, XYL_ERR_PARSE, std::string("malformed GLB: ") + e.what());
    } catch (...) {
        return fail(diag, XYL_ERR_PARSE, "malformed GLB");
    }
}
