// The tuning viewer's panel (view_panel.h): Dear ImGui with its GLFW and OpenGL 3 backends as
// Debian's libimgui-dev ships them. No exception leaves these functions: ImGui throws none, and
// the one std::string (the grammar box) is sized once, well below what could fail.
#include "view_panel.h"

#include <cmath>
#include <cstdio>
#include <cstring>
#include <string>

#include <GLFW/glfw3.h>
#include <imgui.h>
#include <imgui_stdlib.h>
#include <backends/imgui_impl_glfw.h>
#include <backends/imgui_impl_opengl3.h>

namespace {

const double kDeg = 3.14159265358979323846 / 180.0;
std::string g_text;        // the grammar box
std::string g_text_seen;   // params->text when the box last took it
char g_export_base[400] = "xylem-tuned";

const ImVec4 kRed(0.85f, 0.1f, 0.1f, 1.0f);

bool combo(const char *label, int *value, const char *const *names, int count)
{
    bool changed = false;
    if (*value < 0 || *value >= count) *value = 0; /* never index past the names */
    if (ImGui::BeginCombo(label, names[*value])) {
        for (int i = 0; i < count; ++i)
            if (ImGui::Selectable(names[i], i == *value)) *value = i, changed = true;
        ImGui::EndCombo();
    }
    return changed;
}

// A slider's range from a define's own value: [0, 2v] (or [2v, 0]); [-1, 1] around zero.
void define_range(double v, double *lo, double *hi)
{
    if (v > 0) *lo = 0.0, *hi = 2.0 * v;
    else if (v < 0) *lo = 2.0 * v, *hi = 0.0;
    else *lo = -1.0, *hi = 1.0;
}

bool grammar_section(view_params *p, const view_panel_info *info)
{
    bool changed = false;
    const char *current = p->source[0] ? p->source : "(text)";
    if (ImGui::BeginCombo("preset", current)) {
        for (size_t i = 0; i < xyl_lsystem_preset_count(); ++i) {
            const char *name = xyl_lsystem_preset_name(i);
            if (ImGui::Selectable(name, std::strcmp(name, p->source) == 0)) {
                if (view_params_set_text(p, xyl_lsystem_preset_source(name), name)) changed = true;
            }
            if (ImGui::IsItemHovered()) ImGui::SetTooltip("%s", xyl_lsystem_preset_summary(i));
        }
        ImGui::EndCombo();
    }
    const char *text = p->text ? p->text : "";
    if (g_text_seen != text) g_text = g_text_seen = text;
    if (ImGui::InputTextMultiline("##grammar", &g_text, ImVec2(-1.0f, ImGui::GetTextLineHeight() * 10))) {
        // Typing keeps the tuned #defines (a preset or file replaces them).
        uint32_t kept = p->define_count;
        view_define tuned[VIEW_MAX_DEFINES];
        std::memcpy(tuned, p->defines, sizeof tuned);
        if (view_params_set_text(p, g_text.c_str(), "(edited)")) {
            p->define_count = kept;
            std::memcpy(p->defines, tuned, sizeof tuned);
            g_text_seen = g_text;
            changed = true;
        }
    }
    const view_regrow_status &st = info->status;
    if (st.failed && st.failed_stage == VIEW_STAGE_GRAMMAR) {
        char line[160];
        view_text_line(p->text, st.diag.line, line, sizeof line);
        ImGui::PushTextWrapPos(0.0f);
        ImGui::TextColored(kRed, "line %u, column %u: %s", st.diag.line, st.diag.column, st.diag.message);
        ImGui::PopTextWrapPos();
        if (line[0]) ImGui::TextColored(kRed, "> %s", line);
    }

    view_text_define defs[VIEW_MAX_DEFINES];
    uint32_t n = view_text_defines(p->text, defs, VIEW_MAX_DEFINES);
    for (uint32_t i = 0; i < n; ++i) {
        const view_define *tuned = view_params_define(p, defs[i].name);
        double v = tuned ? tuned->value : defs[i].value, lo, hi;
        define_range(defs[i].value, &lo, &hi);
        char label[64];
        std::snprintf(label, sizeof label, "#define %.47s", defs[i].name);
        if (ImGui::SliderScalar(label, ImGuiDataType_Double, &v, &lo, &hi, "%.4g"))
            changed |= view_params_tune_define(p, defs[i].name, v);
    }

    xyl_grammar_info gi;
    std::memset(&gi, 0, sizeof gi);
    if (info->tree) xyl_grammar_get_info(info->tree->grammar, &gi);
    int depth = (int)(p->has_depth ? p->depth : (info->tree ? info->tree->depth : 4));
    if (ImGui::SliderInt("depth", &depth, 0, 16)) p->has_depth = true, p->depth = (uint32_t)depth, changed = true;
    unsigned long long seed = p->has_seed ? p->seed : (info->tree ? info->tree->seed : 1);
    if (ImGui::InputScalar("seed", ImGuiDataType_U64, &seed, nullptr, nullptr, "%llu")) {
        p->has_seed = true, p->seed = seed;
        changed = true;
    }
    float angle = (float)(p->has_angle ? p->angle_deg : (info->tree ? gi.angle / kDeg : 25.0));
    if (ImGui::SliderFloat("angle (deg)", &angle, 0.0f, 180.0f, "%.2f"))
        p->has_angle = true, p->angle_deg = angle, changed = true;
    float step = (float)(p->has_step ? p->step : (info->tree ? gi.step : 1.0));
    if (ImGui::DragFloat("step", &step, 0.01f, 0.001f, 1000.0f, "%.4g", ImGuiSliderFlags_AlwaysClamp))
        p->has_step = true, p->step = step, changed = true;
    bool tropism = p->has_tropism;
    if (ImGui::Checkbox("tune tropism", &tropism)) {
        if (tropism && !p->has_tropism) // start from the grammar's
            for (int k = 0; k < 3; ++k) p->tropism[k] = gi.tropism[k];
        if (tropism && !p->has_tropism) p->tropism[3] = gi.elasticity;
        p->has_tropism = tropism, changed = true;
    }
    if (p->has_tropism) {
        float t[3] = {(float)p->tropism[0], (float)p->tropism[1], (float)p->tropism[2]};
        float e = (float)p->tropism[3];
        if (ImGui::DragFloat3("towards", t, 0.01f, -10.0f, 10.0f, "%.2f")) {
            for (int k = 0; k < 3; ++k) p->tropism[k] = t[k];
            changed = true;
        }
        if (ImGui::SliderFloat("elasticity", &e, -1.0f, 1.0f, "%.3f")) p->tropism[3] = e, changed = true;
    } else if (info->tree) {
        ImGui::SameLine();
        if (gi.elasticity != 0.0)
            ImGui::TextDisabled("grammar: %.3g %.3g %.3g, e %.3g", gi.tropism[0], gi.tropism[1],
                                gi.tropism[2], gi.elasticity);
        else
            ImGui::TextDisabled("grammar: none");
    }
    return changed;
}

bool skeleton_section(view_params *p)
{
    bool changed = false;
    xyl_turtle_desc *t = &p->turtle;
    int mode = (int)t->radius_mode;
    static const char *const radius[] = {"pipe rule", "grammar widths"};
    if (combo("radius", &mode, radius, 2)) t->radius_mode = (xyl_radius_mode)mode, changed = true;
    float n = t->radius_exponent > 0 ? (float)t->radius_exponent : 2.0f;
    if (ImGui::SliderFloat("exponent n", &n, 0.51f, 8.0f, "%.2f")) t->radius_exponent = n, changed = true;
    float tip = (float)t->tip_radius;
    if (ImGui::DragFloat("tip radius", &tip, 0.0005f, 0.0f, 100.0f, tip > 0 ? "%.4g" : "#width / 2",
                         ImGuiSliderFlags_AlwaysClamp))
        t->tip_radius = tip, changed = true;
    bool murray = t->angle_mode == XYL_ANGLES_MURRAY;
    if (ImGui::Checkbox("Murray fork angles", &murray))
        t->angle_mode = murray ? XYL_ANGLES_MURRAY : XYL_ANGLES_GRAMMAR, changed = true;
    if (murray) {
        float lo = (float)((t->murray_min_angle > 0 ? t->murray_min_angle : 10 * kDeg) / kDeg);
        float hi = (float)((t->murray_max_angle > 0 ? t->murray_max_angle : 90 * kDeg) / kDeg);
        if (ImGui::SliderFloat("min angle", &lo, 0.1f, 90.0f, "%.1f deg")) t->murray_min_angle = lo * kDeg, changed = true;
        if (ImGui::SliderFloat("max angle", &hi, 1.0f, 180.0f, "%.1f deg")) t->murray_max_angle = hi * kDeg, changed = true;
    }
    changed |= ImGui::Checkbox("merge collinear F", &t->merge_collinear);
    return changed;
}

bool stems_section(view_params *p)
{
    bool changed = false;
    int sides = p->stems.sides ? (int)p->stems.sides : 4;
    if (ImGui::SliderInt(p->stems.error_world > 0 ? "most ring sides" : "ring sides", &sides, 3, 32))
        p->stems.sides = (uint32_t)sides, changed = true;
    /* 0 is off: every branch gets the sides above; else each branch the fewest within it */
    changed |= ImGui::SliderFloat("sides error (world)", &p->stems.error_world, 0.0f, 10.0f,
                                  p->stems.error_world > 0 ? "%.4g" : "off",
                                  ImGuiSliderFlags_Logarithmic);
    if (p->stems.error_world > 0) changed |= ImGui::Checkbox("error of refined arcs", &p->stems.sides_refined);
    static const char *const subdiv[] = {"none", "Catmull-Clark", "Loop"};
    static const char *const normals[] = {"per branch", "smooth"};
    static const char *const joints[] = {"checked", "unchecked"};
    int s = (int)p->stems.subdivision, nm = (int)p->stems.normals, j = (int)p->stems.joints;
    if (combo("subdivision", &s, subdiv, 3)) p->stems.subdivision = (xyl_subdivision)s, changed = true;
    if (combo("normals", &nm, normals, 2)) p->stems.normals = (xyl_normal_mode)nm, changed = true;
    if (combo("joints", &j, joints, 2)) p->stems.joints = (xyl_joint_check)j, changed = true;
    static const char *const bases[] = {"closed", "open"};
    int b = (int)p->stems.base;
    if (combo("base", &b, bases, 2)) p->stems.base = (xyl_stems_base)b, changed = true;
    changed |= ImGui::SliderFloat("root flare", &p->stems.root_flare, 0.0f, XYL_STEMS_MAX_ROOT_FLARE,
                                  "%.2f");
    return changed;
}

bool refinement_section(view_params *p)
{
    bool changed = false;
    static const char *const variants[] = {"PN (1/3)", "rounded (1/2)", "circle-exact",
                                           "arc (along the branch)"};
    static const char *const paths[] = {"instanced", "hardware (TCS/TES)"};
    int v = (int)p->variant, path = p->path == XYL_TESS_PATH_HARDWARE;
    if (combo("edge handles", &v, variants, XYL_TESS_VARIANT_COUNT)) p->variant = (xyl_tess_variant)v, changed = true;
    if (combo("path", &path, paths, 2)) p->path = path ? XYL_TESS_PATH_HARDWARE : XYL_TESS_PATH_INSTANCED;
    int level = (int)p->level;
    ImGui::SliderInt("fixed level", &level, 0, 64, level ? "%d" : "adaptive");
    p->level = (uint32_t)level;
    if (!p->level)
        ImGui::SliderFloat("budget (px)", &p->error_px, 1.0f / 64, 64.0f, "%.3g", ImGuiSliderFlags_Logarithmic);
    ImGui::Checkbox("wireframe", &p->wireframe);
    return changed;
}

bool foliage_section(view_params *p, const view_panel_info *info)
{
    bool changed = ImGui::Checkbox("leaves", &p->leaves);
    if (!p->leaves) return changed;
    static const char *const draws[] = {"LOD within the budget", "full (every leaf)", "none (CPU only)"};
    int draw = (int)p->leaf_draw;
    if (combo("draw", &draw, draws, 3)) p->leaf_draw = (view_leaf_draw)draw;
    float aspect = p->leaf_aspect > 0 ? p->leaf_aspect : 0.5f;
    if (ImGui::SliderFloat("leaf aspect", &aspect, 0.05f, 2.0f, "%.2f")) p->leaf_aspect = aspect, changed = true;
    if (ImGui::SliderFloat("size jitter", &p->leaf_jitter, 0.0f, 0.9f, "%.2f")) changed = true;
    int sectors = p->leaf_sectors ? (int)p->leaf_sectors : 1;
    if (ImGui::SliderInt("sectors", &sectors, 1, 16)) p->leaf_sectors = (uint32_t)sectors, changed = true;
    const xyl_foliage *f = info->tree ? info->tree->foliage : nullptr;
    if (f) {
        ImGui::Text("%zu leaves, %zu in the LOD array, coarsest %zu", f->original_count, f->leaf_count,
                    f->coarsest_count);
        if (info->has_leaf_pick) {
            char lods[48];
            if (info->leaf_lod_lo == info->leaf_lod_hi) snprintf(lods, sizeof lods, "LOD %u", info->leaf_lod_lo);
            else snprintf(lods, sizeof lods, "LODs %u..%u", info->leaf_lod_lo, info->leaf_lod_hi);
            ImGui::Text("%s this frame: %s of 0..%u, %llu leaves", info->leaves_drawn ? "drawn" : "picked",
                        lods, info->leaf_lod_top, (unsigned long long)info->leaves_picked);
            ImGui::Text("error bound %.3g world units", (double)info->leaf_error);
            if (p->leaf_draw == VIEW_LEAVES_LOD)
                ImGui::TextDisabled("budget: the stems' %.3g px (refinement group)", (double)p->error_px);
            if (info->leaves_drawn && p->wireframe) ImGui::TextDisabled("wireframe: the leaves stay solid");
        }
        if (info->leaf_note) ImGui::TextColored(kRed, "not drawn: %s", info->leaf_note);
    }
    return changed;
}

void scene_section(view_params *p)
{
    static const char *const names[] = {"default", "front", "side", "top", "low"};
    for (int i = 0; i < 5; ++i) {
        if (i) ImGui::SameLine();
        if (ImGui::Button(names[i])) {
            char err[64];
            view_params_set(p, "camera", names[i], err, sizeof err);
        }
    }
    float az = (float)(p->azimuth / kDeg), el = (float)(p->elevation / kDeg);
    if (ImGui::SliderFloat("azimuth", &az, -180.0f, 180.0f, "%.1f deg")) p->azimuth = (float)(az * kDeg);
    if (ImGui::SliderFloat("elevation", &el, -89.0f, 89.0f, "%.1f deg")) p->elevation = (float)(el * kDeg);
    ImGui::SliderFloat("zoom", &p->zoom, 0.05f, 4.0f, "%.2f", ImGuiSliderFlags_Logarithmic);
    ImGui::ColorEdit3("background", p->background);
    if (ImGui::SliderFloat3("light", p->light, -1.0f, 1.0f, "%.2f")) {
        float n = std::sqrt(p->light[0] * p->light[0] + p->light[1] * p->light[1] + p->light[2] * p->light[2]);
        if (n < 1e-6f) p->light[1] = 1.0f, n = 1.0f;
        for (float &c : p->light) c /= n;
    }
}

void export_section(view_panel_result *out, const view_panel_info *info)
{
    ImGui::InputText("file", g_export_base, sizeof g_export_base);
    static const char *const ext[] = {".lsys", ".skel", ".glb", ".png"};
    for (int i = 0; i < 4; ++i) {
        if (i) ImGui::SameLine();
        if (ImGui::Button(ext[i]) && info->tree) {
            out->export_kind = (view_export_kind)(VIEW_EXPORT_LSYS + i);
            std::snprintf(out->export_path, sizeof out->export_path, "%s%s", g_export_base, ext[i]);
        }
    }
    if (info->note) {
        ImGui::PushTextWrapPos(0.0f);
        ImGui::TextUnformatted(info->note);
        ImGui::PopTextWrapPos();
    }
}

// The worker's state: a progress line while it runs, the last failure in red.
void status_lines(const view_panel_info *info)
{
    const view_regrow_status &st = info->status;
    if (st.busy) ImGui::Text("regrowing: %s ... %.0f ms", view_stage_names[st.stage], st.busy_ms);
    else if (!st.failed) ImGui::TextDisabled("tree up to date");
    if (st.failed) {
        ImGui::PushTextWrapPos(0.0f);
        ImGui::TextColored(kRed, "%s failed: %s: %s", view_stage_names[st.failed_stage],
                           xyl_result_string(st.error), st.diag.message);
        ImGui::TextColored(kRed, info->tree ? "showing the last good tree" : "no good tree yet");
        ImGui::PopTextWrapPos();
    }
}

void stats_section(const view_params *p, const view_panel_info *info)
{
    const view_tree *t = info->tree;
    if (!t) return;
    if (ImGui::BeginTable("stages", 2, ImGuiTableFlags_SizingStretchProp)) {
        for (int s = 0; s < VIEW_STAGE_COUNT; ++s) {
            ImGui::TableNextRow();
            ImGui::TableNextColumn();
            ImGui::TextUnformatted(view_stage_names[s]);
            ImGui::TableNextColumn();
            if (s == VIEW_STAGE_FOLIAGE && !t->foliage) ImGui::TextDisabled("off");
            else if (t->ran[s]) ImGui::Text("%.2f ms", t->ms[s]);
            else ImGui::TextDisabled("%.2f ms (kept)", t->ms[s]);
        }
        ImGui::EndTable();
    }
    ImGui::Text("%zu modules, depth %u, seed %llu", xyl_lstring_count(t->string), t->depth,
                (unsigned long long)t->seed);
    ImGui::Text("%zu nodes, %u branches, %zu leaf attachments", t->skeleton->node_count,
                t->skeleton->branch_count, t->skeleton->leaf_count);
    ImGui::Text("mesh: %zu vertices, %zu quads, %zu triangles", t->mesh->vertex_count,
                t->mesh->quad_count, t->mesh->triangle_count);
    if (t->stems_stats.laterals_started_later || t->stems_stats.laterals_hidden)
        ImGui::Text("joints: %u laterals start later, %u hidden whole", t->stems_stats.laterals_started_later,
                    t->stems_stats.laterals_hidden);
    ImGui::Text("drawn: %llu triangles, %llu vertices, levels %u..%u", (unsigned long long)info->triangles,
                (unsigned long long)info->vertices, info->level_lo, info->level_hi);
    if (info->leaves_drawn) {
        if (info->leaf_lod_lo == info->leaf_lod_hi)
            ImGui::Text("leaves drawn: %llu of %zu, LOD %u of 0..%u", (unsigned long long)info->leaves_picked,
                        t->foliage->original_count, info->leaf_lod_lo, info->leaf_lod_top);
        else
            ImGui::Text("leaves drawn: %llu of %zu, LODs %u..%u of 0..%u", (unsigned long long)info->leaves_picked,
                        t->foliage->original_count, info->leaf_lod_lo, info->leaf_lod_hi, info->leaf_lod_top);
    }
    if (p->level) {
        double e = info->error_coefficient / ((double)p->level * p->level);
        ImGui::TextWrapped("level %u: within %.3g world units of the PN surface (%.2g%% of the tree size)", p->level, e,
                    t->patches->size > 0 ? 100.0 * e / t->patches->size : 0.0);
    } else {
        ImGui::TextWrapped("adaptive: every patch within %.3g px of the PN surface", (double)p->error_px);
    }
    if (info->gpu_ms >= 0.0) ImGui::Text("level selection %.3f ms, GPU %.2f ms", info->select_ms, info->gpu_ms);
    else ImGui::Text("level selection %.3f ms, GPU timer pending", info->select_ms);
    if (info->renderer) ImGui::TextDisabled("%s", info->renderer);
}

} // namespace

extern "C" {

bool view_panel_init(GLFWwindow *window)
{
    IMGUI_CHECKVERSION();
    if (!ImGui::CreateContext()) return false;
    ImGui::GetIO().IniFilename = nullptr; // no imgui.ini beside the user's files
    ImGui::StyleColorsLight();
    ImGui::GetStyle().WindowRounding = 0.0f;
    if (!ImGui_ImplGlfw_InitForOpenGL(window, true)) return false;
    return ImGui_ImplOpenGL3_Init("#version 450");
}

void view_panel_shutdown(void)
{
    if (!ImGui::GetCurrentContext()) return;
    ImGui_ImplOpenGL3_Shutdown();
    ImGui_ImplGlfw_Shutdown();
    ImGui::DestroyContext();
}

bool view_panel_wants_mouse(void)
{
    return ImGui::GetCurrentContext() && ImGui::GetIO().WantCaptureMouse;
}

bool view_panel_wants_keyboard(void)
{
    return ImGui::GetCurrentContext() && ImGui::GetIO().WantCaptureKeyboard;
}

void view_panel_frame(view_params *p, const view_panel_info *info, view_panel_result *out)
{
    std::memset(out, 0, sizeof *out);
    ImGui_ImplOpenGL3_NewFrame();
    ImGui_ImplGlfw_NewFrame();
    ImGui::NewFrame();
    if (p->panel) {
        ImGui::SetNextWindowPos(ImVec2(0, 0), ImGuiCond_Always);
        ImGui::SetNextWindowSize(ImVec2(info->width, ImGui::GetIO().DisplaySize.y), ImGuiCond_Always);
        ImGui::Begin("xylem: tune the tree", nullptr,
                     ImGuiWindowFlags_NoMove | ImGuiWindowFlags_NoResize | ImGuiWindowFlags_NoCollapse);
        ImGui::PushItemWidth(-110.0f);
        bool regrow = false;
        status_lines(info);
        if (ImGui::CollapsingHeader("Grammar", ImGuiTreeNodeFlags_DefaultOpen)) regrow |= grammar_section(p, info);
        if (ImGui::CollapsingHeader("Stages and counts", ImGuiTreeNodeFlags_DefaultOpen)) stats_section(p, info);
        if (ImGui::CollapsingHeader("Skeleton")) regrow |= skeleton_section(p);
        if (ImGui::CollapsingHeader("Stems")) regrow |= stems_section(p);
        if (ImGui::CollapsingHeader("Refinement")) regrow |= refinement_section(p);
        if (ImGui::CollapsingHeader("Foliage")) regrow |= foliage_section(p, info);
        if (ImGui::CollapsingHeader("Scene")) scene_section(p);
        if (ImGui::CollapsingHeader("Export")) export_section(out, info);
        ImGui::PopItemWidth();
        ImGui::End();
        out->regrow = regrow;
    }
    ImGui::Render();
    ImGui_ImplOpenGL3_RenderDrawData(ImGui::GetDrawData());
}

} // extern "C"
