/* engine.c — the frame loop (DESIGN.md "Data flow"; ISPM 003_… §3 pipeline). For frame i
 * at t = i / fps: animate the scene (and the previous frame's pose, for motion vectors),
 * update the Embree scene, then per light the shadow map, the eye G-buffer, direct light,
 * (indirect, specular and emission where on), the translucent (alphaMode BLEND) layer where the
 * scene has one, and the composite, which lays that layer over the opaque sum. After each pass
 * it reads the pass's targets back and announces them as named buffers to the listeners
 * (capture is one) by walking the pass's output table (passes.h: name, attachment, components,
 * channels; announce_outputs); buffers made on the CPU (photons.*, progressive.*, specular.*,
 * boundary.weight, gbuffer.emission, translucent.radiance, the methods' extras) are announced by
 * the code that makes them. It never touches files. Per-pass wall time is measured with
 * glFinish at pass boundaries and reported in eng_frame_stats; the read-back for announcing is
 * timed separately as "readback" so pass times stay honest.
 *
 * Owns: the GL context, GPU copies of the scene's primitives, the passes, the Embree scene. */
#define _POSIX_C_SOURCE 200809L /* clock_gettime */
#include "eng_frame.h"
#include "indirect.h"
#include "bsdf.h"
#include "boundary.h"
#include "shadow.h"
#include "progressive.h"
#include "overlap.h"
#include "trace_method.h"
#include "specular.h"
#include "translucent.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#define ENG_MAX_LISTENERS 8

struct eng_engine {
    const scn_scene *scene;
    const seq_sequence *seq;
    eng_settings settings;
    int width, height;
    int32_t camera_node;
    /* A framing camera's key and planes (seq_frame_scene), fixed when the engine is made. */
    seq_camera_key frame_key;
    float frame_znear, frame_zfar;
    eng_glctx *gl;
    eng_rt *rt;
    eng_gpu_prim *gpu;
    GLuint *textures; /* per scene texture */
    pass_gbuffer *gbuffer;
    pass_shadow *shadow;
    void *shadow_state[SHADOW_METHOD_COUNT]; /* shadow.h: every shadow method's state */
    pass_direct *direct;
    pass_composite *composite;
    /* Indirect light (ISPM): random maps, per-light light G-buffer + bounce map, the CPU
     * trace's input and output, photon volumes. */
    eng_random_maps rmaps;
    pass_lightmaps *lightmaps;
    light_maps lmaps[8];
    eng_bounce_photon *bounce;
    size_t bounce_count, bounce_capacity;
    int lineage;            /* eng_desc.lineage: announce photons.origin */
    float *bounce_origin;   /* with lineage: per bounce photon light, face, texel x, y */
    eng_photon_map pmap;
    float *radius; /* per photon r_xy (indirect.h) */
    size_t radius_capacity;
    float *aniso;     /* per photon 4 floats under "kernel_scaling": "anisotropic" (indirect.h) */
    int aniso_on;     /* aniso holds this frame's photons */
    const ind_method *method; /* indirect.h: the `indirect` setting's method, NULL for none */
    void *method_state;
    int method_history; /* the method keeps a history (ind_method.history) */
    const pt_method *tracer; /* trace_method.h: the `photon_trace` setting's method */
    void *tracer_state;
    const spec_method *spec;  /* specular.h: NULL when "off" or the scene has no specular surface */
    void *spec_state;
    pass_translucent *translucent; /* translucent.h: only in scenes with an alphaMode BLEND draw */
    /* Emission seen by the eye (only in scenes with an emissive material): per pixel from the
     * G-buffer's material id, uploaded for the composite. */
    int emissive;
    glu_cpu_target emission;
    float *emission_rgba, *emission_rgb;
    /* Reconstruction filters (DESIGN.md step 7), on when any of splat_subsample > 1,
     * temporal, atrous_iterations is set: G-buffers at 1/2^l resolution (gbuffer_lo[l-1]),
     * upsampling to level l (upsample[l]), temporal accumulation, À-Trous, BSDF resolve. */
    int filtered, levels;
    pass_gbuffer *gbuffer_lo[3];
    pass_upsample *upsample[3];
    pass_temporal *temporal;
    pass_atrous *atrous;
    pass_resolve *resolve;
    /* Progressive accumulation (progressive.h): state, the G-buffer and the method's output
     * read back, and the target the mean is uploaded into. */
    prog_state *prog;
    bnd_pass *bnd; /* the kernel's boundary correction (boundary.h), NULL when off */
    glu_gbuffer prog_gb;
    float *prog_in[2], *prog_mean[2], *prog_count, *prog_radius;
    size_t prog_pixels;
    glu_cpu_target prog_target;
    int prog_target_ok;
    float radius_scale; /* this frame's progressive radius scale (1 without) */
    const float *pixel_scale; /* this frame's per-pixel radius scales (progressive_radius "pixel"), or NULL */
    int next_frame; /* the frame the temporal/progressive history is ready for (frames render in order) */
    int silent;     /* re-rendering earlier frames for the temporal history: announce nothing */
    int history_start; /* eng_set_history_start: where a rebuilt history begins (0: frame 0) */
    int temporal_from; /* the frame the temporal history was last reset at */
    /* `"exposure": "auto"`: settings.exposure holds the resolved stops once exposure_resolved
     * (1: metered at frame 0's composite, exposure_info its metering; 2: eng_set_exposure). */
    int exposure_resolved;
    eng_exposure_key_info exposure_info;
    float *exposure_rgb, *exposure_mask;
    int listener_count;
    eng_listener listeners[ENG_MAX_LISTENERS];
    float *world, *prev_world;
    eng_deform *deform; /* skinned and morphed draws (deform_gl.c) */
    eng_frame_scene fs;
    float *scratch;
    size_t scratch_capacity;
    eng_frame_stats stats;
    double readback_ms;
    eng_overlap *overlap; /* overlap.h: the photon stage's worker beside the GL thread */
};

static double now_ms(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec * 1e3 + (double)ts.tv_nsec * 1e-6;
}

static void upload_scene(eng_engine *e)
{
    const scn_scene *s = e->scene;
    e->gpu = eng_xcalloc(s->primitive_count, sizeof *e->gpu);
    for (uint32_t i = 0; i < s->primitive_count; i++) {
        const scn_primitive *p = &s->primitives[i];
        eng_gpu_prim *g = &e->gpu[i];
        glGenVertexArrays(1, &g->vao);
        glBindVertexArray(g->vao);
        glGenBuffers(1, &g->vbo_pos);
        glBindBuffer(GL_ARRAY_BUFFER, g->vbo_pos);
        glBufferData(GL_ARRAY_BUFFER, (GLsizeiptr)(p->vertex_count * 3 * sizeof(float)), p->positions, GL_STATIC_DRAW);
        glVertexAttribPointer(0, 3, GL_FLOAT, GL_FALSE, 0, NULL);
        glEnableVertexAttribArray(0);
        /* The previous frame's position (gbuffer.vert.glsl): the same for a rigid primitive,
         * whose motion comes from prev_world; deform_gl.c's own buffer for a deformed one. */
        glVertexAttribPointer(5, 3, GL_FLOAT, GL_FALSE, 0, NULL);
        glEnableVertexAttribArray(5);
        glGenBuffers(1, &g->vbo_nrm);
        glBindBuffer(GL_ARRAY_BUFFER, g->vbo_nrm);
        glBufferData(GL_ARRAY_BUFFER, (GLsizeiptr)(p->vertex_count * 3 * sizeof(float)), p->normals, GL_STATIC_DRAW);
        glVertexAttribPointer(1, 3, GL_FLOAT, GL_FALSE, 0, NULL);
        glEnableVertexAttribArray(1);
        /* TEXCOORD_0/1 and COLOR_0 where the primitive has them (base_color.glsl). */
        const float *extra[3] = {p->texcoords[0], p->texcoords[1], p->colors};
        GLuint *vbo[3] = {&g->vbo_uv[0], &g->vbo_uv[1], &g->vbo_col};
        for (int a = 0; a < 3; a++) {
            if (!extra[a])
                continue;
            int comps = a == 2 ? 4 : 2;
            glGenBuffers(1, vbo[a]);
            glBindBuffer(GL_ARRAY_BUFFER, *vbo[a]);
            glBufferData(GL_ARRAY_BUFFER, (GLsizeiptr)(p->vertex_count * comps * sizeof(float)), extra[a], GL_STATIC_DRAW);
            glVertexAttribPointer((GLuint)(2 + a), comps, GL_FLOAT, GL_FALSE, 0, NULL);
            glEnableVertexAttribArray((GLuint)(2 + a));
        }
        if (p->tangents) { /* normal maps (normal_map.glsl) */
            glGenBuffers(1, &g->vbo_tan);
            glBindBuffer(GL_ARRAY_BUFFER, g->vbo_tan);
            glBufferData(GL_ARRAY_BUFFER, (GLsizeiptr)(p->vertex_count * 4 * sizeof(float)), p->tangents, GL_STATIC_DRAW);
            glVertexAttribPointer(6, 4, GL_FLOAT, GL_FALSE, 0, NULL);
            glEnableVertexAttribArray(6);
        }
        glGenBuffers(1, &g->ibo);
        glBindBuffer(GL_ELEMENT_ARRAY_BUFFER, g->ibo);
        glBufferData(GL_ELEMENT_ARRAY_BUFFER, (GLsizeiptr)(p->index_count * sizeof(uint32_t)), p->indices, GL_STATIC_DRAW);
        g->index_count = (GLsizei)p->index_count;
        glBindVertexArray(0);
    }
    /* Textures as the loader decoded them (linear RGBA floats, row 0 = v 0), with the mip
     * levels the loader built where their minFilter asks for them (texture_mip.c: the CPU
     * samples the same levels). */
    e->textures = eng_xcalloc(s->texture_count, sizeof *e->textures);
    for (uint32_t i = 0; i < s->texture_count; i++) {
        const scn_texture *t = &s->textures[i];
        static const GLint wraps[] = {GL_REPEAT, GL_CLAMP_TO_EDGE, GL_MIRRORED_REPEAT};
        glGenTextures(1, &e->textures[i]);
        glBindTexture(GL_TEXTURE_2D, e->textures[i]);
        glPixelStorei(GL_UNPACK_ALIGNMENT, 4);
        glTexImage2D(GL_TEXTURE_2D, 0, GL_RGBA32F, (GLsizei)t->width, (GLsizei)t->height, 0, GL_RGBA, GL_FLOAT,
                     t->texels);
        for (uint32_t l = 1; l < t->levels; l++) {
            GLsizei w = (GLsizei)(t->width >> l), h = (GLsizei)(t->height >> l);
            glTexImage2D(GL_TEXTURE_2D, (GLint)l, GL_RGBA32F, w ? w : 1, h ? h : 1, 0, GL_RGBA, GL_FLOAT, t->mips[l]);
        }
        glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAX_LEVEL, t->levels ? (GLint)t->levels - 1 : 0);
        glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, t->min_filter);
        glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, t->mag_linear ? GL_LINEAR : GL_NEAREST);
        glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_S, wraps[t->wrap_s]);
        glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_T, wraps[t->wrap_t]);
    }
    glBindTexture(GL_TEXTURE_2D, 0);
    e->deform = eng_deform_create(s, e->gpu);
}

/* The part of eng_create that calls no GL: the ray tracer's scene and, for
 * an indirect method, the random maps. It writes only e->rt, e->rmaps and its own fields. */
typedef struct cpu_setup {
    eng_engine *e;
    int random_maps;
    eng_result r;
    eng_error err;
} cpu_setup;

static void cpu_setup_run(void *arg)
{
    cpu_setup *cs = arg;
    eng_engine *e = cs->e;
    cs->r = rt_create(e->scene, e->settings.threads, &e->rt, &cs->err);
    if (cs->r == ENG_OK && cs->random_maps)
        cs->r = rmap_create((uint64_t)e->settings.random_seed, (uint32_t)e->settings.random_map_size, &e->rmaps,
                            &cs->err);
}

eng_result eng_create(const eng_desc *desc, eng_engine **out, eng_error *err)
{
    *out = NULL;
    const scn_scene *s = desc->scene;
    const seq_sequence *q = desc->sequence;
    eng_engine *e = eng_xcalloc(1, sizeof *e);
    e->scene = s;
    e->seq = q;
    e->lineage = desc->lineage;
    e->pmap.want_source = desc->lineage;
    e->settings = q->settings;
    eng_settings_defaults(&e->settings);
    e->width = q->width;
    e->height = q->height;
    e->camera_node = -1;
    if (q->camera_node[0]) {
        e->camera_node = scn_find_node(s, q->camera_node);
        if (e->camera_node < 0 || s->nodes[e->camera_node].camera < 0) {
            eng_destroy(e);
            return eng_fail(err, ENG_ERR_INVALID, "%s: camera node \"%s\" is not a camera node of %s", q->path,
                            q->camera_node, s->path);
        }
    } else if (q->camera_by_index) {
        for (uint32_t i = 0; i < s->node_count && e->camera_node < 0; i++)
            if (s->nodes[i].source == q->camera_node_index)
                e->camera_node = (int32_t)i;
        if (e->camera_node < 0 || s->nodes[e->camera_node].camera < 0) {
            eng_destroy(e);
            return eng_fail(err, ENG_ERR_INVALID, "%s: camera node %d is not a camera node in the scene played of %s",
                            q->path, q->camera_node_index, s->path);
        }
    }
    if (e->camera_node < 0 && q->camera_frame)
        seq_frame_scene(q, s, &e->frame_key, &e->frame_znear, &e->frame_zfar);
    uint32_t nlights = 0;
    for (uint32_t i = 0; i < s->node_count; i++)
        if (s->nodes[i].light >= 0)
            nlights++;
    if (nlights > 8) {
        eng_destroy(e);
        return eng_fail(err, ENG_ERR_UNSUPPORTED, "%s: %u light nodes; the engine handles at most 8", s->path, nlights);
    }

    eng_pin_determinism(e->settings.threads);
    /* Embree's scene and the random maps need no GL: with 2+ threads they are built on the
     * overlap worker while this thread creates the GL context and builds the programs. */
    e->method = ind_method_find(eng_indirect_name(e->settings.indirect));
    e->overlap = ovl_create(e->settings.threads);
    cpu_setup cs = {e, e->method != NULL, ENG_OK, {{0}}};
    ovl_start(e->overlap, cpu_setup_run, &cs);
    eng_result r = glctx_create_on(desc->gl, desc->gl_use_device, desc->gl_device, &e->gl, err);
    if (r == ENG_OK)
        r = pass_gbuffer_create(e->width, e->height, &e->gbuffer, err);
    if (r == ENG_OK)
        r = pass_shadow_create(e->settings.shadow_map_size, nlights, &e->shadow, err);
    for (int m = 0; m < SHADOW_METHOD_COUNT && r == ENG_OK; m++)
        r = shadow_methods[m]->create(&e->settings, nlights, &e->shadow_state[m], err);
    if (r == ENG_OK)
        r = pass_direct_create(e->width, e->height, e->settings.pcss_blocker == ENG_PCSS_RAYS, &e->direct, err);
    if (r == ENG_OK)
        r = pass_composite_create(e->width, e->height, &e->composite, err);
    ovl_join(e->overlap);
    if (r == ENG_OK && cs.r != ENG_OK) {
        r = cs.r;
        if (err)
            *err = cs.err;
    }
    if (r == ENG_OK && e->method) {
        r = pass_lightmaps_create(&e->rmaps, &e->lightmaps, err);
        const eng_settings *st = &e->settings;
        e->filtered = st->splat_subsample > 1 || st->temporal || st->atrous_iterations > 0;
        int w = e->width, h = e->height;
        while ((1 << e->levels) < st->splat_subsample && e->levels < 3) {
            e->levels++;
            if (r == ENG_OK) /* level l+1 is level l's G-buffer halved, rounded up */
                r = pass_upsample_create(w, h, &e->upsample[e->levels - 1], err);
            w = (w + 1) / 2;
            h = (h + 1) / 2;
            if (r == ENG_OK)
                r = pass_gbuffer_create(w, h, &e->gbuffer_lo[e->levels - 1], err);
        }
        if (r == ENG_OK)
            r = e->method->create(w, h, e->filtered, &e->method_state, err);
        e->method_history = e->method->history && e->method->history(st);
        e->tracer = pt_method_find(eng_trace_name(st->photon_trace));
        if (r == ENG_OK)
            r = e->tracer->create(st, &e->tracer_state, err);
        if (r == ENG_OK && st->temporal)
            r = pass_temporal_create(e->width, e->height, &e->temporal, err);
        if (r == ENG_OK && st->atrous_iterations > 0)
            r = pass_atrous_create(e->width, e->height, st->atrous_iterations, &e->atrous, err);
        if (r == ENG_OK && e->filtered)
            r = pass_resolve_create(e->width, e->height, &e->resolve, err);
        if (r == ENG_OK && st->progressive_pixel && (!st->progressive || !e->method->per_pixel_radius))
            r = eng_fail(err, ENG_ERR_INVALID,
                         "settings.progressive_radius \"pixel\" needs \"progressive\": true and indirect "
                         "\"kd-gather\", \"tile-gather\", \"ispm\" or \"quads\" (got \"%s\")",
                         e->method->name);
        if (r == ENG_OK && st->progressive) {
            e->prog = prog_create();
            prog_set_per_pixel(e->prog, st->progressive_pixel);
            r = glu_cpu_target_create(&e->prog_target, w, h, e->filtered, err);
            e->prog_target_ok = r == ENG_OK;
        }
        if (r == ENG_OK && st->boundary == ENG_BOUNDARY_RENORMALIZE && e->method->traced_gather)
            r = eng_fail(err, ENG_ERR_INVALID,
                         "settings.boundary \"renormalize\" corrects a kernel at the pixel; \"%s\" has none",
                         e->method->name);
        if (r == ENG_OK && st->boundary == ENG_BOUNDARY_RENORMALIZE)
            r = bnd_pass_create(w, h, e->filtered ? 2 : 1, &e->bnd, err);
    }
    e->spec = eye_scene_has_specular(s) ? spec_method_find(eng_specular_name(e->settings.specular)) : NULL;
    if (r == ENG_OK && e->spec)
        r = e->spec->create(e->width, e->height, &e->spec_state, err);
    if (r == ENG_OK && tl_scene_has_blend(s))
        r = pass_translucent_create(e->width, e->height, &e->translucent, err);
    for (uint32_t i = 0; i < s->material_count; i++)
        if (s->materials[i].emissive[0] > 0.0f || s->materials[i].emissive[1] > 0.0f ||
            s->materials[i].emissive[2] > 0.0f)
            e->emissive = 1;
    if (r == ENG_OK && e->emissive) {
        size_t n = (size_t)e->width * (size_t)e->height;
        e->emission_rgba = eng_xcalloc(n * 4, sizeof(float));
        e->emission_rgb = eng_xcalloc(n * 3, sizeof(float));
        r = glu_cpu_target_create(&e->emission, e->width, e->height, 0, err);
        if (r != ENG_OK)
            e->emissive = 0;
    }
    e->radius_scale = 1.0f;
    if (r != ENG_OK) {
        eng_destroy(e);
        return r;
    }
    upload_scene(e);

    e->world = eng_xcalloc((size_t)s->node_count * 16, sizeof(float));
    e->prev_world = eng_xcalloc((size_t)s->node_count * 16, sizeof(float));
    uint32_t ndraws = 0;
    for (uint32_t i = 0; i < s->node_count; i++)
        if (s->nodes[i].mesh >= 0)
            ndraws += s->meshes[s->nodes[i].mesh].primitive_count;
    e->fs.scene = s;
    e->fs.gpu = e->gpu;
    e->fs.textures = e->textures;
    e->fs.draws = eng_xcalloc(ndraws, sizeof(eng_draw));
    e->fs.draw_count = ndraws;
    e->fs.lights = eng_xcalloc(nlights, sizeof(eng_light_pose));
    e->fs.light_count = nlights;
    *out = e;
    return ENG_OK;
}

void eng_destroy(eng_engine *e)
{
    if (!e)
        return;
    ovl_destroy(e->overlap);
    if (e->gl) {
        for (int i = 0; i < 8; i++)
            light_maps_release(&e->lmaps[i]);
        pass_lightmaps_destroy(e->lightmaps);
        if (e->method && e->method_state)
            e->method->destroy(e->method_state);
        if (e->tracer)
            e->tracer->destroy(e->tracer_state);
        if (e->spec && e->spec_state)
            e->spec->destroy(e->spec_state);
        pass_translucent_destroy(e->translucent);
        if (e->emissive)
            glu_cpu_target_destroy(&e->emission);
        for (int l = 0; l < 3; l++) {
            pass_gbuffer_destroy(e->gbuffer_lo[l]);
            pass_upsample_destroy(e->upsample[l]);
        }
        pass_temporal_destroy(e->temporal);
        pass_atrous_destroy(e->atrous);
        pass_resolve_destroy(e->resolve);
        if (e->prog_target_ok)
            glu_cpu_target_destroy(&e->prog_target);
        pass_composite_destroy(e->composite);
        pass_direct_destroy(e->direct);
        pass_shadow_destroy(e->shadow);
        for (int m = 0; m < SHADOW_METHOD_COUNT; m++)
            shadow_methods[m]->destroy(e->shadow_state[m]);
        pass_gbuffer_destroy(e->gbuffer);
        if (e->textures)
            glDeleteTextures((GLsizei)e->scene->texture_count, e->textures);
        eng_deform_destroy(e->deform);
        if (e->gpu)
            for (uint32_t i = 0; i < e->scene->primitive_count; i++) {
                glDeleteBuffers(1, &e->gpu[i].vbo_pos);
                glDeleteBuffers(1, &e->gpu[i].vbo_nrm);
                glDeleteBuffers(1, &e->gpu[i].ibo);
                glDeleteBuffers(2, e->gpu[i].vbo_uv);
                glDeleteBuffers(1, &e->gpu[i].vbo_col);
                glDeleteBuffers(1, &e->gpu[i].vbo_tan);
                glDeleteVertexArrays(1, &e->gpu[i].vao);
            }
    }
    rt_destroy(e->rt);
    glctx_destroy(e->gl);
    rmap_destroy(&e->rmaps);
    photon_map_free(&e->pmap);
    free(e->bounce);
    free(e->bounce_origin);
    free(e->radius);
    free(e->aniso);
    prog_destroy(e->prog);
    bnd_pass_destroy(e->bnd);
    glu_gbuffer_free(&e->prog_gb);
    for (int a = 0; a < 2; a++) {
        free(e->prog_in[a]);
        free(e->prog_mean[a]);
    }
    free(e->prog_count);
    free(e->prog_radius);
    free(e->textures);
    free(e->emission_rgba);
    free(e->emission_rgb);
    free(e->gpu);
    free(e->world);
    free(e->prev_world);
    free(e->fs.draws);
    free(e->fs.lights);
    free(e->scratch);
    free(e->exposure_rgb);
    free(e->exposure_mask);
    free(e);
}

eng_result eng_add_listener(eng_engine *e, const eng_listener *l)
{
    if (e->listener_count >= ENG_MAX_LISTENERS)
        return ENG_ERR_INVALID;
    e->listeners[e->listener_count++] = *l;
    return ENG_OK;
}

const char *eng_gl_version(const eng_engine *e) { return glctx_version(e->gl); }
const char *eng_gl_renderer(const eng_engine *e) { return glctx_renderer(e->gl); }
const char *eng_gl_backend(const eng_engine *e) { return glctx_backend_name(e->gl); }
const char *eng_gl_where(const eng_engine *e) { return glctx_where(e->gl); }

/* ---------------------------------------------------------------- scene at time t */

static void camera_at(const eng_engine *e, const float *world, double t, eng_view *v)
{
    float aspect = (float)e->width / (float)e->height;
    if (e->camera_node >= 0) {
        const scn_camera *c = &e->scene->cameras[e->scene->nodes[e->camera_node].camera];
        const float *w = world + 16 * (size_t)e->camera_node;
        if (!m4_invert(v->view, w))
            m4_identity(v->view);
        v->eye[0] = w[12];
        v->eye[1] = w[13];
        v->eye[2] = w[14];
        v->znear = c->znear;
        v->zfar = c->zfar;
        m4_perspective(v->proj, c->yfov, aspect, c->znear, c->zfar);
    } else {
        const seq_sequence *q = e->seq;
        const seq_camera_key *k = q->camera_frame ? &e->frame_key : q->camera_keys;
        int n = q->camera_frame ? 1 : q->camera_key_count;
        float znear = q->camera_frame ? e->frame_znear : q->camera_znear;
        float zfar = q->camera_frame ? e->frame_zfar : q->camera_zfar;
        float pos[3], tgt[3];
        int i = 0;
        while (i + 1 < n && k[i + 1].time <= t)
            i++;
        double a = 0.0;
        if (i + 1 < n && t > k[i].time)
            a = (t - k[i].time) / (k[i + 1].time - k[i].time);
        const seq_camera_key *k1 = i + 1 < n ? &k[i + 1] : &k[i];
        for (int c = 0; c < 3; c++) {
            pos[c] = (float)((1.0 - a) * k[i].position[c] + a * k1->position[c]);
            tgt[c] = (float)((1.0 - a) * k[i].target[c] + a * k1->target[c]);
        }
        m4_look_at(v->view, pos, tgt, q->camera_up);
        memcpy(v->eye, pos, sizeof pos);
        v->znear = znear;
        v->zfar = zfar;
        m4_perspective(v->proj, q->camera_yfov, aspect, znear, zfar);
    }
    m4_mul(v->view_proj, v->proj, v->view);
}

static void pose_frame(eng_engine *e, int frame)
{
    const scn_scene *s = e->scene;
    double t = seq_frame_time(e->seq, frame);
    double tp = frame > 0 ? seq_frame_time(e->seq, frame - 1) : t;
    scn_evaluate(s, t, e->world);
    scn_evaluate(s, tp, e->prev_world);
    eng_frame_scene *fs = &e->fs;
    uint32_t d = 0, l = 0;
    for (int c = 0; c < 3; c++) {
        fs->bounds_min[c] = INFINITY;
        fs->bounds_max[c] = -INFINITY;
    }
    for (uint32_t i = 0; i < s->node_count; i++) {
        const scn_node *n = &s->nodes[i];
        const float *w = e->world + 16 * (size_t)i;
        if (n->mesh >= 0) {
            const scn_mesh *m = &s->meshes[n->mesh];
            for (uint32_t k = 0; k < m->primitive_count; k++) {
                eng_draw *dr = &fs->draws[d++];
                dr->primitive = m->first_primitive + k;
                dr->material = s->primitives[dr->primitive].material;
                memcpy(dr->world, w, sizeof dr->world);
                memcpy(dr->prev_world, e->prev_world + 16 * (size_t)i, sizeof dr->prev_world);
                dr->gpu = &e->gpu[dr->primitive];
                dr->positions = dr->normals = dr->tangents = NULL;
            }
        }
    }
    eng_deform_pose(e->deform, fs, e->world, e->prev_world, t, tp);
    for (uint32_t k = 0; k < d; k++) {
        const eng_draw *dr = &fs->draws[k];
        const float *pos = eng_draw_positions(s, dr);
        for (uint32_t v = 0; v < s->primitives[dr->primitive].vertex_count; v++) {
            float q[3];
            m4_transform_point(dr->world, pos + 3 * v, q);
            for (int c = 0; c < 3; c++) {
                fs->bounds_min[c] = fminf(fs->bounds_min[c], q[c]);
                fs->bounds_max[c] = fmaxf(fs->bounds_max[c], q[c]);
            }
        }
    }
    if (d == 0)
        for (int c = 0; c < 3; c++)
            fs->bounds_min[c] = fs->bounds_max[c] = 0.0f;
    for (uint32_t i = 0; i < s->node_count; i++) {
        const scn_node *n = &s->nodes[i];
        if (n->light < 0)
            continue;
        const scn_light *sl = &s->lights[n->light];
        const float *w = e->world + 16 * (size_t)i;
        eng_light_pose *lp = &fs->lights[l++];
        lp->type = sl->type;
        lp->position[0] = w[12];
        lp->position[1] = w[13];
        lp->position[2] = w[14];
        /* KHR_lights_punctual: spot and directional lights point down the node's −Z. */
        double dir[3] = {-w[8], -w[9], -w[10]};
        double len = sqrt(dir[0] * dir[0] + dir[1] * dir[1] + dir[2] * dir[2]);
        for (int c = 0; c < 3; c++) {
            lp->direction[c] = (float)(len > 0 ? dir[c] / len : (c == 1 ? -1.0 : 0.0));
            lp->radiance_scale[c] = sl->color[c] * sl->intensity;
        }
        lp->range = sl->range;
        lp->inner_cone = sl->inner_cone;
        lp->outer_cone = sl->outer_cone;
        lp->radius = sl->radius;
        if (sl->type == SCN_LIGHT_DIRECTIONAL) {
            /* The ortho shadow box's near plane: one scene radius behind the centre. */
            float half = 0.0f, centre[3];
            for (int c = 0; c < 3; c++) {
                centre[c] = 0.5f * (fs->bounds_min[c] + fs->bounds_max[c]);
                float ext = 0.5f * (fs->bounds_max[c] - fs->bounds_min[c]);
                half += ext * ext;
            }
            half = sqrtf(half) * 1.01f + 0.01f;
            for (int c = 0; c < 3; c++)
                lp->position[c] = centre[c] - lp->direction[c] * half;
        }
    }
    camera_at(e, e->world, t, &fs->camera);
    camera_at(e, e->prev_world, tp, &fs->prev_camera);
}

/* ---------------------------------------------------------------- announcing */

static int announce(eng_engine *e, int frame, const char *name, int w, int h, int nch,
                    const char *const *channels, const float *data)
{
    if (e->silent)
        return 0;
    eng_buffer b = {name, w, h, nch, channels, data};
    for (int i = 0; i < e->listener_count; i++)
        if (e->listeners[i].buffer && e->listeners[i].buffer(e->listeners[i].user, frame, &b) != 0)
            return 1;
    return 0;
}

/* Makes e->scratch hold at least n floats. */
static void scratch_reserve(eng_engine *e, size_t n)
{
    if (n <= e->scratch_capacity)
        return;
    free(e->scratch);
    e->scratch = eng_xcalloc(n, sizeof(float));
    e->scratch_capacity = n;
}

/* Reads attachment `index` (layer `layer`) of t with the components in pick, and announces
 * it unless the sequence does not capture it. Returns non-zero if a listener aborted. */
static int read_and_announce(eng_engine *e, int frame, const char *name, const glu_target *t, int index,
                             int layer, int nch, const int *pick, const char *const *channels)
{
    if (e->silent || !seq_wants(e->seq, name))
        return 0;
    scratch_reserve(e, (size_t)t->width * (size_t)t->height * (size_t)nch);
    double t0 = now_ms();
    glu_read(t, index, layer, nch, pick, e->scratch);
    e->readback_ms += now_ms() - t0;
    return announce(e, frame, name, t->width, t->height, nch, channels, e->scratch);
}

#define OUT_NAME 96 /* room for any output's name (pass_output_name) */

/* Assembles table entry o (a PASS_OUT_CPU one, named `name`) on the CPU and announces it
 * unless the sequence does not capture it; called whether or not it is captured, since some
 * assemble what later passes use. Returns non-zero if a listener aborted. */
typedef int (*cpu_output_fn)(eng_engine *e, int frame, const pass_output *o, const char *name, void *user);

/* Announces the outputs of a pass's table (passes.h) in table order: each read back from
 * target t (layer at->face; at NULL: layer 0, no placeholders) unless the sequence does not
 * capture it, optional entries only when `optional` is set, CPU entries through cpu (skipped
 * when NULL). Returns non-zero if a listener aborted, the buffer's name in name[OUT_NAME]. */
static int announce_outputs(eng_engine *e, int frame, const pass_output *table, const glu_target *t,
                            const pass_output_at *at, int optional, cpu_output_fn cpu, void *user, char *name)
{
    for (const pass_output *o = table; o->name; o++) {
        if (o->optional && !optional)
            continue;
        if (pass_output_name(o, at, name, OUT_NAME) != 0) {
            fprintf(stderr, "ispm: output table entry %s does not expand\n", o->name);
            abort();
        }
        int aborted = o->attachment == PASS_OUT_CPU
                          ? cpu && cpu(e, frame, o, name, user)
                          : read_and_announce(e, frame, name, t, o->attachment, at ? at->face : 0,
                                              pass_output_channels(o), o->pick, o->channels);
        if (aborted)
            return 1;
    }
    return 0;
}

static void add_time(eng_engine *e, const char *pass, double ms)
{
    eng_frame_stats *st = &e->stats;
    for (int i = 0; i < st->pass_count; i++)
        if (strcmp(st->passes[i].name, pass) == 0) {
            st->passes[i].ms += ms;
            return;
        }
    if (st->pass_count < ENG_MAX_PASSES) {
        snprintf(st->passes[st->pass_count].name, sizeof st->passes[0].name, "%s", pass);
        st->passes[st->pass_count++].ms = ms;
    }
}

static const char *const CH_RGB[] = {"R", "G", "B"};
static const char *const CH_PHOTON[] = {"position.X", "position.Y", "position.Z", "direction.X", "direction.Y",
                                        "direction.Z", "power.R", "power.G", "power.B", "normal.X",
                                        "normal.Y", "normal.Z", "density", "bounce"};
static const char *const CH_Y[] = {"Y"};

/* Light l's shadow views into this frame's stats (eng_light_record), with the texel size
 * pass_direct.c gives the shaders. */
static void record_light(eng_engine *e, uint32_t l, const shadow_map *sm)
{
    if (l >= ENG_MAX_LIGHT_RECORDS)
        return;
    const eng_light_pose *lp = &e->fs.lights[l];
    eng_light_record *r = &e->stats.lights[l];
    r->type = lp->type == SCN_LIGHT_POINT ? 0 : lp->type == SCN_LIGHT_SPOT ? 1 : 2;
    r->faces = sm->faces;
    memcpy(r->position, lp->position, sizeof r->position);
    memcpy(r->direction, lp->direction, sizeof r->direction);
    r->texel = pass_direct_shadow_texel(lp, sm, &e->settings);
    r->far_value = sm->far_value;
    for (int f = 0; f < sm->faces && f < 6; f++)
        memcpy(r->view_proj[f], sm->view_proj[f], sizeof r->view_proj[f]);
    if ((int)l + 1 > e->stats.light_count)
        e->stats.light_count = (int)l + 1;
}

/* Runs light l's shadow method after its shadow map (shadow.h), timed as the method's pass,
 * and announces the map it returns per face through the method's output table. */
static eng_result shadow_method_pass(eng_engine *e, int frame, uint32_t l, const shadow_map *sm,
                                     const glu_target **out, eng_error *err)
{
    int m = shadow_method_index(&e->fs.lights[l]);
    const shadow_method *method = shadow_methods[m];
    double t0 = now_ms();
    int failed = 0;
    *out = method->run(e->shadow_state[m], &e->fs.lights[l], sm, l, &failed);
    glFinish();
    if (method->pass)
        add_time(e, method->pass, now_ms() - t0);
    if (failed)
        return eng_fail(err, ENG_ERR_GL, "frame %d: cannot allocate the %s map of light %u", frame, method->name, l);
    for (int f = 0; *out && method->outputs && f < sm->faces; f++) {
        char name[OUT_NAME];
        pass_output_at at = {l, sm->faces, f, 0, NULL};
        if (announce_outputs(e, frame, method->outputs, *out, &at, 0, NULL, NULL, name))
            return eng_fail(err, ENG_ERR_ABORTED, "frame %d: capture failed at %s", frame, name);
    }
    return ENG_OK;
}

/* gbuffer.material (a cpu_output_fn; user: the eye G-buffer): five channels from two
 * attachments, the material parameters (3) and the id (4.y). */
static int material_assemble(eng_engine *e, int frame, const pass_output *o, const char *name, void *user)
{
    const glu_target *gb = user;
    if (e->silent || !seq_wants(e->seq, name))
        return 0;
    static const int mat_pick[] = {0, 1, 2, 3};
    size_t npix = (size_t)gb->width * (size_t)gb->height;
    scratch_reserve(e, npix * 6);
    float *mat = e->scratch;
    float *id = e->scratch + npix * 5;
    double r0 = now_ms();
    glu_read(gb, 4, 0, 1, (const int[]){1}, id);
    float *params = malloc(npix * 4 * sizeof(float));
    if (!params) {
        fprintf(stderr, "ispm: out of memory\n");
        abort();
    }
    glu_read(gb, 3, 0, 4, mat_pick, params);
    for (size_t i = 0; i < npix; i++) {
        memcpy(mat + i * 5, params + i * 4, 4 * sizeof(float));
        mat[i * 5 + 4] = id[i];
    }
    free(params);
    e->readback_ms += now_ms() - r0;
    return announce(e, frame, name, gb->width, gb->height, pass_output_channels(o), o->channels, mat);
}

/* Whether a light of this frame has a size (direct.penumbra is announced only then, so that
 * runs of punctual lights keep today's buffers). */
static int any_sized_light(const eng_frame_scene *fs)
{
    for (uint32_t l = 0; l < fs->light_count; l++)
        if (fs->lights[l].radius > 0.0f)
            return 1;
    return 0;
}

#define PHOTON_ROW 1024 /* photons.map is PHOTON_ROW photons wide */

/* The power a light sends into the scene, per channel averaged: what its share of the
 * photon budget follows (ISPM §4.2: bounce map size ∝ Φ_L / Φ_T). */
static double light_power(const eng_light_pose *l, const eng_frame_scene *fs)
{
    double c = (l->radiance_scale[0] + l->radiance_scale[1] + l->radiance_scale[2]) / 3.0;
    if (l->type == SCN_LIGHT_POINT)
        return 4.0 * ENG_PI * c;
    if (l->type == SCN_LIGHT_SPOT) /* solid angle of the outer cone (the falloff is ignored) */
        return 2.0 * ENG_PI * (1.0 - cos(l->outer_cone)) * c;
    double half = 0.0;
    for (int i = 0; i < 3; i++) {
        double ext = 0.5 * (fs->bounds_max[i] - fs->bounds_min[i]);
        half += ext * ext;
    }
    return c * 4.0 * half; /* E × area of the box's face, (2·half)² */
}

/* One face of a light's maps while light_passes walks pass_lightmaps_outputs: the bounce
 * target's readback buffers. */
typedef struct bounce_face {
    const light_maps *lm;
    uint32_t light;
    int face, size;
    size_t npix;
    float *pos, *pw, *dir, *lobe, *bounce;
} bounce_face;

/* bounce.light<i>[.face<f>] (a cpu_output_fn): reads the face's light G-buffer positions and
 * bounce target back, gathers its surviving photons into e->bounce for the CPU trace, and
 * announces the bounce map. */
static int bounce_assemble(eng_engine *e, int frame, const pass_output *o, const char *name, void *user)
{
    bounce_face *bf = user;
    static const int p4[] = {0, 1, 2, 3};
    const light_maps *lm = bf->lm;
    const uint32_t l = bf->light;
    const int f = bf->face, size = bf->size;
    const size_t npix = bf->npix;
    float *pos = bf->pos, *pw = bf->pw, *dir = bf->dir, *lobe = bf->lobe, *bounce = bf->bounce;
    double r0 = now_ms();
    glu_read(&lm->gbuffer, 0, f, 4, p4, pos);
    glu_read(&lm->bounce, 0, f, 4, p4, pw);
    glu_read(&lm->bounce, 1, f, 4, p4, dir);
    glu_read(&lm->bounce, 2, f, 1, p4, lobe);
    e->readback_ms += now_ms() - r0;
    for (size_t i = 0; i < npix; i++) {
        memcpy(bounce + 8 * i, pw + 4 * i, 3 * sizeof(float));
        memcpy(bounce + 8 * i + 3, dir + 4 * i, 3 * sizeof(float));
        bounce[8 * i + 6] = pw[4 * i + 3];
        bounce[8 * i + 7] = dir[4 * i + 3];
        if (pos[4 * i + 3] == 0.0f || (pw[4 * i] <= 0.0f && pw[4 * i + 1] <= 0.0f && pw[4 * i + 2] <= 0.0f))
            continue;
        if (e->bounce_origin) {
            float *org = e->bounce_origin + 4 * e->bounce_count;
            org[0] = (float)l;
            org[1] = (float)f;
            org[2] = (float)(i % (size_t)size);
            org[3] = (float)(i / (size_t)size);
        }
        eng_bounce_photon *b = &e->bounce[e->bounce_count++];
        memcpy(b->position, pos + 4 * i, 3 * sizeof(float));
        memcpy(b->direction, dir + 4 * i, 3 * sizeof(float));
        memcpy(b->power, pw + 4 * i, 3 * sizeof(float));
        b->path_density = pw[4 * i + 3];
        b->ior = dir[4 * i + 3];
        b->delta = lobe[i] >= (float)BSDF_LOBE_MIRROR;
    }
    if (seq_wants(e->seq, name))
        return announce(e, frame, name, size, size, pass_output_channels(o), o->channels, bounce);
    return 0;
}

/* Light G-buffers and bounce maps of every light (ISPM §3 1b–c), announced; the surviving
 * bounce-map photons are gathered in e->bounce for the CPU trace. Returns non-zero when a
 * listener aborted (err set). */
static eng_result light_passes(eng_engine *e, int frame, const eng_rmap_frame *rf, eng_error *err)
{
    eng_frame_scene *fs = &e->fs;
    double total = 0.0;
    for (uint32_t l = 0; l < fs->light_count; l++)
        total += light_power(&fs->lights[l], fs);
    /* Map sizes first, so the photon list is allocated once. */
    int sizes[8];
    size_t need = 0;
    for (uint32_t l = 0; l < fs->light_count; l++) {
        double share = total > 0.0 ? light_power(&fs->lights[l], fs) / total : 0.0;
        int faces = fs->lights[l].type == SCN_LIGHT_POINT ? 6 : 1;
        /* Round the texel count up to a square per face; the texels' solid angles make the
         * power exact whatever the size (see shaders/bounce.frag.glsl). */
        sizes[l] = (int)ceil(sqrt(share * e->settings.photon_count / faces));
        if (sizes[l] < 1)
            sizes[l] = 1;
        need += (size_t)sizes[l] * (size_t)sizes[l] * (size_t)faces;
    }
    if (need > e->bounce_capacity) {
        free(e->bounce);
        e->bounce = eng_xmalloc(need * sizeof *e->bounce);
        free(e->bounce_origin);
        e->bounce_origin = e->lineage ? eng_xmalloc(need * 4 * sizeof(float)) : NULL;
        e->bounce_capacity = need;
    }
    e->bounce_count = 0;
    for (uint32_t l = 0; l < fs->light_count; l++) {
        int size = sizes[l];
        double t0 = now_ms();
        light_maps *lm = &e->lmaps[l];
        eng_result r = pass_lightmaps_run(e->lightmaps, fs, l, size, rf, lm, err);
        glFinish();
        add_time(e, "lightmaps", now_ms() - t0);
        if (r != ENG_OK)
            return r;
        int faces = lm->views.faces;
        size_t npix = (size_t)size * (size_t)size;
        bounce_face bf = {.lm = lm,
                          .light = l,
                          .size = size,
                          .npix = npix,
                          .pos = eng_xmalloc(npix * 4 * sizeof(float)),
                          .pw = eng_xmalloc(npix * 4 * sizeof(float)),
                          .dir = eng_xmalloc(npix * 4 * sizeof(float)),
                          .lobe = eng_xmalloc(npix * sizeof(float)),
                          .bounce = eng_xmalloc(npix * 8 * sizeof(float))};
        int aborted = 0;
        for (int f = 0; f < faces && !aborted; f++) {
            char name[OUT_NAME];
            pass_output_at at = {l, faces, f, 0, NULL};
            bf.face = f;
            aborted = announce_outputs(e, frame, pass_lightmaps_outputs, &lm->gbuffer, &at, 0, bounce_assemble, &bf,
                                       name);
        }
        free(bf.pos);
        free(bf.pw);
        free(bf.dir);
        free(bf.lobe);
        free(bf.bounce);
        if (aborted)
            return eng_fail(err, ENG_ERR_ABORTED, "frame %d: capture failed in the light passes", frame);
    }
    return ENG_OK;
}

/* photons.map: one photon per pixel of a PHOTON_ROW-wide image, unused pixels zero. */
static int announce_photon_map(eng_engine *e, int frame)
{
    if (!seq_wants(e->seq, "photons.map"))
        return 0;
    size_t n = e->pmap.count;
    int rows = (int)((n + PHOTON_ROW - 1) / PHOTON_ROW);
    if (rows < 1)
        rows = 1;
    float *img = calloc((size_t)rows * PHOTON_ROW * 14, sizeof(float));
    if (!img) {
        fprintf(stderr, "ispm: out of memory\n");
        abort();
    }
    for (size_t i = 0; i < n; i++) {
        const eng_photon *p = &e->pmap.photons[i];
        float *d = img + 14 * i;
        memcpy(d, p->position, 3 * sizeof(float));
        memcpy(d + 3, p->direction, 3 * sizeof(float));
        memcpy(d + 6, p->power, 3 * sizeof(float));
        memcpy(d + 9, p->normal, 3 * sizeof(float));
        d[12] = p->path_density;
        d[13] = (float)p->bounce;
    }
    int rc = announce(e, frame, "photons.map", PHOTON_ROW, rows, 14, CH_PHOTON, img);
    free(img);
    return rc;
}

/* photons.origin (with eng_desc.lineage): per photons.map pixel the light, face and texel
 * (x, y, top row first as bounce.light<i>[.face<f>]) of the bounce-map photon whose path stored
 * it, and its kernel radius r_xy this frame (ind_photon_radii), so ispm lineage can recompute
 * every photon's contribution with the engine's kernel. Unused pixels hold light −1. */
static int announce_photon_origin(eng_engine *e, int frame)
{
    static const char *const CH_ORIGIN[] = {"light", "face", "texel.X", "texel.Y", "radius"};
    if (!e->lineage || !seq_wants(e->seq, "photons.origin"))
        return 0;
    size_t n = e->pmap.count;
    int rows = (int)((n + PHOTON_ROW - 1) / PHOTON_ROW);
    if (rows < 1)
        rows = 1;
    size_t px = (size_t)rows * PHOTON_ROW;
    float *img = eng_xmalloc(px * 5 * sizeof(float));
    for (size_t i = 0; i < px; i++) {
        float *d = img + 5 * i;
        if (i < n) {
            memcpy(d, e->bounce_origin + 4 * (size_t)e->pmap.source[i], 4 * sizeof(float));
            d[4] = e->radius[i];
        } else {
            d[0] = -1.0f;
            d[1] = d[2] = d[3] = d[4] = 0.0f;
        }
    }
    int rc = announce(e, frame, "photons.origin", PHOTON_ROW, rows, 5, CH_ORIGIN, img);
    free(img);
    return rc;
}

/* Prepares the photon-trace method for this frame (trace_method.h), timed as its pass when it
 * names one, announces the buffers it lists and records its frame info; *tracer gets what the
 * trace calls per ray. */
static eng_result trace_prepare(eng_engine *e, int frame, pt_tracer *tracer, eng_error *err)
{
    double t0 = now_ms();
    eng_result r = e->tracer->prepare(e->tracer_state, e->rt, &e->fs, tracer, err);
    if (e->tracer->pass)
        add_time(e, e->tracer->pass, now_ms() - t0);
    if (r != ENG_OK)
        return r;
    e->tracer->frame_info(e->tracer_state, &e->stats);
    eng_buffer b;
    for (int i = 0; e->tracer->buffer(e->tracer_state, i, &b); i++)
        if (seq_wants(e->seq, b.name) &&
            announce(e, frame, b.name, b.width, b.height, b.channel_count, b.channels, b.data))
            return eng_fail(err, ENG_ERR_ABORTED, "frame %d: capture failed at %s", frame, b.name);
    return ENG_OK;
}

/* The photon stage of a frame (ISPM §3 1d and the kernel radii): the CPU photon trace from the
 * bounce maps, then every photon's r_xy (and anisotropic kernel). It reads only the posed
 * scene, the bounce photons and the traced geometry and writes only the photon map, the radii
 * and its own fields, so it may run on the overlap worker (overlap.h) while the GL thread
 * renders the eye G-buffer and the direct light; it calls no GL and announces nothing. */
typedef struct photon_stage {
    eng_engine *e;
    pt_tracer tracer;
    eng_trace_settings ts;
    eng_trace_stats tstats;
    eng_result r;
    eng_error err;
    double trace_ms;
} photon_stage;

static void photon_stage_run(void *arg)
{
    photon_stage *ps = arg;
    eng_engine *e = ps->e;
    double t0 = now_ms();
    ps->r = photon_trace_with(&ps->tracer, &e->fs, &e->rmaps, e->bounce, e->bounce_count, &ps->ts, &e->pmap,
                              &ps->tstats, &ps->err);
    ps->trace_ms = now_ms() - t0;
    if (ps->r != ENG_OK)
        return;
    if (e->pmap.count > e->radius_capacity) {
        free(e->radius);
        e->radius = eng_xmalloc(e->pmap.count * sizeof *e->radius);
        free(e->aniso);
        e->aniso = e->settings.kernel_scaling == ENG_SCALING_ANISOTROPIC
                       ? eng_xmalloc(e->pmap.count * 4 * sizeof *e->aniso)
                       : NULL;
        e->radius_capacity = e->pmap.count;
    }
    ind_photon_radii(&e->pmap, &e->settings, &e->fs, e->width, e->height, e->radius_scale, e->radius);
    e->aniso_on = e->aniso && ind_photon_aniso(&e->pmap, &e->settings, e->aniso);
    if (e->method->reserve)
        e->method->reserve(e->method_state, e->pmap.count, e->settings.threads);
}

/* The first frame's photon buffers and the indirect method's (reserve), grown to a guess at
 * the map's size: the bounce-map photons and a quarter more (cornell-box-perf: 65,536, 72,670
 * stored); the trace and the method grow them further when they need to. */
static void photon_warm_run(void *arg)
{
    eng_engine *e = arg;
    const size_t n = (size_t)e->settings.photon_count;
    photon_map_reserve(&e->pmap, e->settings.threads, n + n / 4);
    if (e->method->reserve)
        e->method->reserve(e->method_state, n + n / 4, e->settings.threads);
}

/* Announces the photon stage's results after ovl_join: its trace time, statistics and
 * photons.map / photons.origin. */
static eng_result photon_stage_finish(eng_engine *e, int frame, photon_stage *ps, eng_error *err)
{
    add_time(e, "photons", ps->trace_ms);
    if (ps->r != ENG_OK) {
        if (err)
            *err = ps->err;
        return ps->r;
    }
    e->stats.trace = ps->tstats.counts;
    e->stats.photons_emitted = ps->tstats.emitted;
    memcpy(e->stats.photons_stored, ps->tstats.stored, sizeof e->stats.photons_stored);
    e->stats.photons_truncated = ps->tstats.truncated;
    if (announce_photon_map(e, frame))
        return eng_fail(err, ENG_ERR_ABORTED, "frame %d: capture failed at photons.map", frame);
    if (announce_photon_origin(e, frame))
        return eng_fail(err, ENG_ERR_ABORTED, "frame %d: capture failed at photons.origin", frame);
    return ENG_OK;
}

/* Runs the indirect method against gb (indirect.h), timed as the method's pass, and announces
 * the extra buffers it lists; *out gets its target. */
static eng_result run_method(eng_engine *e, int frame, const glu_target *gb, const glu_target **out, eng_error *err)
{
    /* Per-pixel progressive radii (progressive.h): this frame's scales for the G-buffer gb. */
    e->pixel_scale = NULL;
    if (e->prog && e->settings.progressive_pixel) {
        glu_gbuffer_read(gb, &e->prog_gb);
        e->pixel_scale = prog_pixel_scales(e->prog, &e->prog_gb);
    }
    eng_rmap_frame rf;
    rmap_frame(&e->settings, frame, &rf);
    ind_input in = {&e->fs, gb, &e->pmap, e->radius, &e->settings, e->aniso_on ? e->aniso : NULL, e->pixel_scale,
                    e->rt, &e->rmaps, &rf};
    ind_output o;
    memset(&o, 0, sizeof o);
    double t0 = now_ms();
    eng_result r = e->method->run(e->method_state, &in, &o, err);
    glFinish();
    add_time(e, e->method->pass, now_ms() - t0);
    if (r != ENG_OK)
        return r;
    for (int i = 0; i < o.extra_count; i++) {
        const ind_extra *x = &o.extra[i];
        if (seq_wants(e->seq, x->name) &&
            announce(e, frame, x->name, x->width, x->height, x->channels, x->channel_names, x->data))
            return eng_fail(err, ENG_ERR_ABORTED, "frame %d: capture failed at %s", frame, x->name);
    }
    *out = o.target;
    return ENG_OK;
}

/* The kernel's boundary correction (boundary.h) of the method's output *sp against the
 * G-buffer gb it ran on; *sp becomes the corrected target, boundary.weight is announced. */
static eng_result boundary_run(eng_engine *e, int frame, const glu_target *gb, const glu_target **sp, eng_error *err)
{
    if (!e->bnd)
        return ENG_OK;
    double t0 = now_ms();
    ind_input in = {&e->fs, gb, &e->pmap, e->radius, &e->settings, NULL, e->pixel_scale, NULL, NULL, NULL};
    const float *wt = bnd_pass_run(e->bnd, gb, sp, &in);
    glFinish();
    add_time(e, "boundary", now_ms() - t0);
    if (announce(e, frame, "boundary.weight", gb->width, gb->height, 1, CH_Y, wt))
        return eng_fail(err, ENG_ERR_ABORTED, "frame %d: capture failed in the boundary pass", frame);
    return ENG_OK;
}

/* Progressive accumulation (progressive.h) of the method's output *sp against the G-buffer gb
 * it ran on: reads both back, adds the frame to the running mean, uploads the mean into a
 * target of the same layout, announces progressive.{radiance,count,radius} and replaces *sp
 * with it. The same for every method (it sees only the method's output target). */
static eng_result progressive_run(eng_engine *e, int frame, const glu_target *gb, const glu_target **sp,
                                  eng_error *err)
{
    static const int p4[] = {0, 1, 2, 3};
    double t0 = now_ms();
    const int w = gb->width, h = gb->height, na = e->filtered ? 2 : 1;
    const size_t n = (size_t)w * (size_t)h;
    if (e->prog_pixels != n) {
        for (int a = 0; a < 2; a++) {
            free(e->prog_in[a]);
            free(e->prog_mean[a]);
            e->prog_in[a] = eng_xmalloc(n * 4 * sizeof(float));
            e->prog_mean[a] = eng_xmalloc(n * 4 * sizeof(float));
        }
        free(e->prog_count);
        free(e->prog_radius);
        e->prog_count = eng_xmalloc(n * sizeof(float));
        e->prog_radius = eng_xmalloc(n * sizeof(float));
        e->prog_pixels = n;
    }
    glu_gbuffer_read(gb, &e->prog_gb);
    for (int a = 0; a < na; a++)
        glu_read(*sp, a, 0, 4, p4, e->prog_in[a]);
    prog_accumulate(e->prog, &e->prog_gb, na, (const float *const *)e->prog_in, e->prog_mean, e->prog_count,
                    e->prog_radius);
    for (int a = 0; a < na; a++)
        glu_cpu_target_upload(&e->prog_target, a, e->prog_mean[a]);
    glFinish();
    add_time(e, "progressive", now_ms() - t0);
    *sp = &e->prog_target.target;
    static const int p012[] = {0, 1, 2};
    if (read_and_announce(e, frame, "progressive.radiance", *sp, 0, 0, 3, p012, CH_RGB) ||
        announce(e, frame, "progressive.count", w, h, 1, CH_Y, e->prog_count) ||
        announce(e, frame, "progressive.radius", w, h, 1, CH_Y, e->prog_radius) ||
        (e->settings.progressive_pixel &&
         announce(e, frame, "progressive.photons", w, h, 1, CH_Y, prog_photons(e->prog))))
        return eng_fail(err, ENG_ERR_ABORTED, "frame %d: capture failed in the progressive pass", frame);
    return ENG_OK;
}

/* What the eye sees in and through mirrors and glass (specular.h), announced as specular.*;
 * *tex gets the radiance texture the composite adds. */
static eng_result specular_pass(eng_engine *e, int frame, const glu_target *gb, GLuint *tex, eng_error *err)
{
    static const char *const CH_RGB3[] = {"R", "G", "B"}, *const CH_Y1[] = {"Y"};
    spec_input in = {&e->fs, e->rt, gb, e->method ? &e->pmap : NULL, e->radius, &e->settings};
    spec_output out;
    double t0 = now_ms();
    eng_result r = e->spec->run(e->spec_state, &in, &out, err);
    glFinish();
    add_time(e, "specular", now_ms() - t0);
    if (r != ENG_OK)
        return r;
    const char *names[3] = {"specular.radiance", "specular.depth", "specular.throughput"};
    const float *data[3] = {out.radiance, out.depth, out.throughput};
    for (int k = 0; k < 3; k++)
        if (seq_wants(e->seq, names[k]) && announce(e, frame, names[k], gb->width, gb->height, k == 1 ? 1 : 3,
                                                    k == 1 ? CH_Y1 : CH_RGB3, data[k]))
            return eng_fail(err, ENG_ERR_ABORTED, "frame %d: capture failed at %s", frame, names[k]);
    *tex = out.target->color[0];
    return ENG_OK;
}

/* The translucent surfaces (translucent.h), announced as translucent.radiance (premultiplied
 * RGBA); *tex gets the texture the composite lays over the opaque result. */
static eng_result translucent_pass(eng_engine *e, int frame, const glu_target *gb, GLuint *tex, eng_error *err)
{
    static const char *const CH_RGBA[] = {"R", "G", "B", "A"};
    const float *rgba;
    double t0 = now_ms();
    eng_result r = pass_translucent_run(e->translucent, &e->fs, e->rt, gb, e->method ? &e->pmap : NULL, e->radius,
                                        &e->settings, &rgba, tex, err);
    glFinish();
    add_time(e, "translucent", now_ms() - t0);
    if (r != ENG_OK)
        return r;
    if (seq_wants(e->seq, "translucent.radiance") &&
        announce(e, frame, "translucent.radiance", gb->width, gb->height, 4, CH_RGBA, rgba))
        return eng_fail(err, ENG_ERR_ABORTED, "frame %d: capture failed at translucent.radiance", frame);
    return ENG_OK;
}

/* The emitted radiance of the surface each pixel shows (the G-buffer's attachment 5:
 * emissiveFactor × strength × emissive texture), announced as gbuffer.emission; *tex gets the
 * texture the composite adds. Emitters are seen, not light sources: they send no photons and no shadow rays. */
static eng_result emission_pass(eng_engine *e, int frame, const glu_target *gb, GLuint *tex, eng_error *err)
{
    static const char *const CH_RGB3[] = {"R", "G", "B"};
    double t0 = now_ms();
    glu_read(gb, 5, 0, 3, (const int[]){0, 1, 2}, e->emission_rgb);
    size_t n = (size_t)gb->width * (size_t)gb->height;
    for (size_t i = 0; i < n; i++) {
        for (int c = 0; c < 3; c++)
            e->emission_rgba[4 * i + (size_t)c] = e->emission_rgb[3 * i + (size_t)c];
        e->emission_rgba[4 * i + 3] = 1.0f;
    }
    glu_cpu_target_upload(&e->emission, 0, e->emission_rgba);
    glFinish();
    add_time(e, "emission", now_ms() - t0);
    if (seq_wants(e->seq, "gbuffer.emission") &&
        announce(e, frame, "gbuffer.emission", gb->width, gb->height, 3, CH_RGB3, e->emission_rgb))
        return eng_fail(err, ENG_ERR_ABORTED, "frame %d: capture failed at gbuffer.emission", frame);
    *tex = e->emission.target.color[0];
    return ENG_OK;
}

/* The indirect light through the reconstruction filters (DESIGN.md steps 6–7): G-buffers at
 * the subsampled levels, photon volumes as irradiance at the coarsest level, upsampling level
 * by level, temporal accumulation, À-Trous, and the BSDF. Announces every level; *tex gets
 * the texture of indirect.radiance. */
static eng_result filtered_indirect(eng_engine *e, int frame, const glu_target *gb, GLuint *tex, eng_error *err)
{
    const eng_settings *s = &e->settings;
    const glu_target *lvl[4] = {gb, NULL, NULL, NULL};
    char name[OUT_NAME];
    pass_output_at at = {0, 1, 0, 0, e->method->prefix};
    int aborted = 0;
    double t0 = now_ms();
    for (int l = 1; l <= e->levels; l++)
        lvl[l] = pass_gbuffer_run(e->gbuffer_lo[l - 1], &e->fs);
    glFinish();
    if (e->levels)
        add_time(e, "gbuffer_lo", now_ms() - t0);
    for (int l = 1; l <= e->levels && !aborted; l++) {
        at.level = l;
        aborted = announce_outputs(e, frame, pass_gbuffer_level_outputs, lvl[l], &at, 0, NULL, NULL, name);
    }
    const glu_target *sp = NULL;
    if (aborted)
        return eng_fail(err, ENG_ERR_ABORTED, "frame %d: capture failed in the filter passes", frame);
    eng_result r = run_method(e, frame, lvl[e->levels], &sp, err);
    if (r != ENG_OK)
        return r;
    aborted = announce_outputs(e, frame, ind_irradiance_outputs, sp, &at, 0, NULL, NULL, name);
    if (!aborted && (r = boundary_run(e, frame, lvl[e->levels], &sp, err)) != ENG_OK)
        return r;
    if (!aborted && e->prog && (r = progressive_run(e, frame, lvl[e->levels], &sp, err)) != ENG_OK)
        return r;
    GLuint irradiance = sp->color[0], glossy = sp->color[1];
    for (int l = e->levels - 1; l >= 0 && !aborted; l--) {
        t0 = now_ms();
        const glu_target *up = pass_upsample_run(e->upsample[l], lvl[l + 1], irradiance, glossy, lvl[l]);
        glFinish();
        add_time(e, "upsample", now_ms() - t0);
        at.level = l;
        aborted = announce_outputs(e, frame, pass_upsample_outputs, up, &at, 0, NULL, NULL, name);
        irradiance = up->color[0];
        glossy = up->color[1];
    }
    if (e->temporal && !aborted) {
        t0 = now_ms();
        const glu_target *tt = pass_temporal_run(e->temporal, gb, irradiance, s->temporal_alpha);
        glFinish();
        add_time(e, "temporal", now_ms() - t0);
        aborted = announce_outputs(e, frame, pass_temporal_outputs, tt, NULL, 0, NULL, NULL, name);
        irradiance = tt->color[0];
    }
    if (e->atrous && !aborted) {
        t0 = now_ms();
        const glu_target *lv = pass_atrous_run(e->atrous, gb, irradiance, s->atrous_detail, s->atrous_gamma);
        glFinish();
        add_time(e, "atrous", now_ms() - t0);
        int n = s->atrous_iterations;
        for (int i = 0; i < n && !aborted; i++) {
            at.level = i;
            aborted = announce_outputs(e, frame, pass_atrous_outputs, &lv[i], &at, 0, NULL, NULL, name);
        }
        aborted = aborted || announce_outputs(e, frame, pass_atrous_result_outputs, &lv[n - 1], NULL, 0, NULL, NULL,
                                              name);
        irradiance = lv[n - 1].color[3];
    }
    if (aborted)
        return eng_fail(err, ENG_ERR_ABORTED, "frame %d: capture failed in the filter passes", frame);
    t0 = now_ms();
    const glu_target *rs = pass_resolve_run(e->resolve, gb, irradiance, glossy);
    glFinish();
    add_time(e, "resolve", now_ms() - t0);
    if (announce_outputs(e, frame, pass_resolve_outputs, rs, NULL, 0, NULL, NULL, name))
        return eng_fail(err, ENG_ERR_ABORTED, "frame %d: capture failed at indirect.radiance", frame);
    *tex = rs->color[0];
    return ENG_OK;
}

/* Forgets the temporal and progressive state: the next frame (from) starts them anew. */
static void history_reset(eng_engine *e, int from)
{
    if (e->temporal)
        pass_temporal_reset(e->temporal);
    if (e->prog)
        prog_reset(e->prog);
    if (e->method_history)
        e->method->reset(e->method_state);
    e->temporal_from = from;
}

/* `"exposure": "auto"` at frame 0's composite (ran with settings.exposure 0): meters the linear
 * radiance over the pixels the eye G-buffer covers (position.w is 1 on a surface, 0 on the
 * background; eng_exposure_key), fixes settings.exposure at the result for this and every later
 * frame, and runs the composite again so that frame 0's display uses it too (its radiance
 * attachment is the same bits: the exposure only enters the display transform). */
static const glu_target *meter_exposure(eng_engine *e, const glu_target *gb, const glu_target *comp, GLuint direct,
                                        GLuint indirect, GLuint specular, GLuint emission, GLuint translucent)
{
    size_t n = (size_t)comp->width * (size_t)comp->height;
    if (!e->exposure_rgb) {
        e->exposure_rgb = eng_xcalloc(3 * n, sizeof(float));
        e->exposure_mask = eng_xcalloc(n, sizeof(float));
    }
    static const int rgb[3] = {0, 1, 2}, w[1] = {3};
    glu_read(comp, 0, 0, 3, rgb, e->exposure_rgb);
    glu_read(gb, 0, 0, 1, w, e->exposure_mask);
    eng_exposure_key(e->exposure_rgb, e->exposure_mask, n, &e->exposure_info);
    e->settings.exposure = e->exposure_info.stops;
    e->exposure_resolved = 1;
    comp = pass_composite_run(e->composite, direct, indirect, specular, emission, translucent, &e->settings);
    glFinish();
    return comp;
}

int eng_exposure(const eng_engine *e, float *stops, eng_exposure_key_info *info)
{
    if (info)
        *info = e->exposure_info;
    if (stops)
        *stops = e->settings.exposure;
    return e->settings.exposure_auto ? e->exposure_resolved : 0;
}

void eng_set_exposure(eng_engine *e, float stops)
{
    if (!e->settings.exposure_auto)
        return;
    e->settings.exposure = stops;
    e->exposure_resolved = 2;
    memset(&e->exposure_info, 0, sizeof e->exposure_info);
}

/* The earliest frame the state of frame `frame` depends on (eng_frame_stats): the last
 * temporal reset, or the progressive accumulation's last global restart, whichever is earlier
 * (the state depends on both); -1 without a stateful pass. */
static int history_from(const eng_engine *e, int frame)
{
    int from = -1;
    if (e->temporal || e->method_history)
        from = e->temporal_from;
    if (e->prog) {
        int p = frame - prog_frames(e->prog) + 1;
        if (from < 0 || p < from)
            from = p;
    }
    return from;
}

void eng_set_history_start(eng_engine *e, int first)
{
    e->history_start = first > 0 ? first : 0;
    e->next_frame = -1; /* the next frame rebuilds its history from there */
}

int eng_stateful(const eng_engine *e)
{
    return e->temporal || e->prog || e->method_history;
}

eng_result eng_render_frame(eng_engine *e, int frame, eng_error *err)
{
    if (frame < 0 || frame >= e->seq->frame_count)
        return eng_fail(err, ENG_ERR_INVALID, "%s: frame %d outside 0..%d", e->seq->path, frame, e->seq->frame_count - 1);
    const int window = e->settings.temporal_window;
    if (e->settings.exposure_auto && !e->exposure_resolved && frame != 0) {
        /* "auto" is metered at frame 0 whatever frame comes first (a shard, a resumed run
         * without a recorded value): frame 0 is rendered without announcing, then any history
         * is rebuilt as if it had not been. */
        int silent = e->silent;
        e->silent = 1;
        eng_result r = eng_render_frame(e, 0, err);
        e->silent = silent;
        if (r != ENG_OK)
            return r;
        e->next_frame = -1;
    }
    if (eng_stateful(e) && !e->silent && frame != e->next_frame) {
        /* Frame i's temporal (or progressive) result depends on every earlier frame (since the
         * last temporal_window boundary): asked for frames out of order (e.g. record --resume,
         * or a shard's first frame), rebuild the history from frame 0 (or the window's start,
         * or eng_set_history_start's frame) without announcing, so the result is the same as
         * in an uninterrupted run (for a shard: as one whose history began there). */
        int from = frame >= e->history_start ? e->history_start : 0;
        if (window > 0 && frame / window * window > from)
            from = frame / window * window;
        history_reset(e, from);
        e->silent = 1;
        for (int k = from; k < frame; k++) {
            eng_result r = eng_render_frame(e, k, err);
            if (r != ENG_OK) {
                e->silent = 0;
                return r;
            }
        }
        e->silent = 0;
    }
    /* temporal_window: every state restarts at a multiple of the window (a bounded history,
     * so that a shard's warm-up of at most window - 1 frames reproduces it bit for bit). */
    if (eng_stateful(e) && window > 0 && frame % window == 0)
        history_reset(e, frame);
    double t = seq_frame_time(e->seq, frame);
    memset(&e->stats, 0, sizeof e->stats);
    e->stats.frame = frame;
    e->stats.time = t;
    e->readback_ms = 0.0;
    for (int i = 0; i < e->listener_count && !e->silent; i++)
        if (e->listeners[i].frame_begin && e->listeners[i].frame_begin(e->listeners[i].user, frame, t) != 0)
            return eng_fail(err, ENG_ERR_ABORTED, "frame %d: a listener refused the frame", frame);

    double t0 = now_ms();
    pose_frame(e, frame);
    rt_update(e->rt, &e->fs);
    add_time(e, "scene", now_ms() - t0);
    memcpy(e->stats.camera_view_proj, e->fs.camera.view_proj, sizeof e->stats.camera_view_proj);
    memcpy(e->stats.camera_eye, e->fs.camera.eye, sizeof e->stats.camera_eye);

    /* With 2+ threads the first trace's photon buffers are grown and touched on the overlap
     * worker while this thread renders the shadow and bounce maps. */
    if (e->method && e->overlap && e->pmap.capacity == 0)
        ovl_start(e->overlap, photon_warm_run, e);

    /* Shadow maps, one per light. */
    const shadow_map *maps[8] = {0};
    const glu_target *shadow_extra[8] = {0}; /* the shadow method's map per light (shadow.h) */
    for (uint32_t l = 0; l < e->fs.light_count; l++) {
        t0 = now_ms();
        maps[l] = pass_shadow_run(e->shadow, &e->fs, l);
        glFinish();
        add_time(e, "shadow", now_ms() - t0);
        if (!maps[l])
            return eng_fail(err, ENG_ERR_GL, "frame %d: cannot allocate the shadow map of light %u", frame, l);
        record_light(e, l, maps[l]);
        for (int f = 0; f < maps[l]->faces; f++) {
            char name[OUT_NAME];
            pass_output_at at = {l, maps[l]->faces, f, 0, NULL};
            if (announce_outputs(e, frame, pass_shadow_outputs, &maps[l]->target, &at, 0, NULL, NULL, name))
                return eng_fail(err, ENG_ERR_ABORTED, "frame %d: capture failed at %s", frame, name);
        }
        eng_result r = shadow_method_pass(e, frame, l, maps[l], &shadow_extra[l], err);
        if (r != ENG_OK)
            return r;
    }

    /* Light G-buffers, bounce maps (ISPM §3 1b–c), then the photon stage (the CPU photon trace,
     * 1d, and the kernel radii) on the overlap worker while this thread renders the eye
     * G-buffer and the direct light, which do not read photons (overlap.h); their buffers are
     * announced after the join, in the order of a serial frame. */
    photon_stage ps;
    memset(&ps, 0, sizeof ps);
    int staged = 0;
    if (e->method) {
        eng_rmap_frame rf; /* salt and stratum of this frame (002 §4.2), for both processors */
        rmap_frame(&e->settings, frame, &rf);
        eng_result r = light_passes(e, frame, &rf, err);
        ovl_join(e->overlap); /* photon_warm_run */
        if (r != ENG_OK)
            return r;
        eng_trace_settings ts = {e->settings.bounces, e->settings.threads, rf.salt, rf.stratified,
                                 {rf.offset[0], rf.offset[1], rf.offset[2], rf.offset[3]},
                                 2.0f * e->settings.kernel_radius};
        ps.e = e;
        ps.ts = ts;
        if ((r = trace_prepare(e, frame, &ps.tracer, err)) != ENG_OK)
            return r;
        /* Progressive photon mapping's radius scale (progressive.h): one per frame. */
        e->radius_scale = e->prog ? prog_begin(e->prog, &e->fs) : 1.0f;
        add_time(e, "photons", 0.0); /* the passes keep a serial frame's order */
        ovl_start(e->overlap, photon_stage_run, &ps);
        staged = 1;
    }

    /* Eye G-buffer and direct light, rendered. */
    t0 = now_ms();
    const glu_target *gb = pass_gbuffer_run(e->gbuffer, &e->fs);
    glFinish();
    add_time(e, "gbuffer", now_ms() - t0);
    t0 = now_ms();
    const glu_target *direct = pass_direct_run(e->direct, &e->fs, gb, maps, shadow_extra, &e->settings);
    glFinish();
    add_time(e, "direct", now_ms() - t0);

    if (staged) {
        ovl_join(e->overlap);
        eng_result r = photon_stage_finish(e, frame, &ps, err);
        if (r != ENG_OK)
            return r;
    }

    /* Eye G-buffer, announced. */
    char name[OUT_NAME];
    if (announce_outputs(e, frame, pass_gbuffer_outputs, gb, NULL, 0, material_assemble, (void *)gb, name))
        return eng_fail(err, ENG_ERR_ABORTED, "frame %d: capture failed in the gbuffer pass", frame);

    /* Direct light, announced. */
    if (announce_outputs(e, frame, pass_direct_outputs, direct, NULL, any_sized_light(&e->fs), NULL, NULL, name))
        return eng_fail(err, ENG_ERR_ABORTED, "frame %d: capture failed at %s", frame, name);

    /* Indirect light: the photon estimate of the `indirect` method (ISPM §3 step 4), at full
     * resolution, or reconstructed by the filters. */
    GLuint indirect_tex = 0;
    if (e->method && e->filtered) {
        eng_result r = filtered_indirect(e, frame, gb, &indirect_tex, err);
        if (r != ENG_OK)
            return r;
    } else if (e->method) {
        const glu_target *sp = NULL;
        eng_result r = run_method(e, frame, gb, &sp, err);
        if (r != ENG_OK)
            return r;
        indirect_tex = sp->color[0];
        pass_output_at at = {0, 1, 0, 0, e->method->prefix};
        int aborted = announce_outputs(e, frame, ind_radiance_outputs, sp, &at, 0, NULL, NULL, name);
        if (!aborted && (r = boundary_run(e, frame, gb, &sp, err)) != ENG_OK)
            return r;
        indirect_tex = sp->color[0];
        if (!aborted && e->prog) {
            r = progressive_run(e, frame, gb, &sp, err);
            if (r != ENG_OK)
                return r;
            indirect_tex = sp->color[0];
        }
        /* Without the filters the method's (or boundary or progressive) target has the
         * resolve's layout: indirect.radiance in attachment 0. */
        aborted = aborted || announce_outputs(e, frame, pass_resolve_outputs, sp, NULL, 0, NULL, NULL, name);
        if (aborted)
            return eng_fail(err, ENG_ERR_ABORTED, "frame %d: capture failed in the %s pass", frame, e->method->pass);
    }

    /* Specular eye paths (003 §3 step 5), only in scenes with a mirror or glass. */
    GLuint specular_tex = 0, emission_tex = 0, translucent_tex = 0;
    if (e->spec) {
        eng_result r = specular_pass(e, frame, gb, &specular_tex, err);
        if (r != ENG_OK)
            return r;
    }
    if (e->emissive) {
        eng_result r = emission_pass(e, frame, gb, &emission_tex, err);
        if (r != ENG_OK)
            return r;
    }
    /* Translucent surfaces, back to front over the opaque result (003 §3 step 5). */
    if (e->translucent) {
        eng_result r = translucent_pass(e, frame, gb, &translucent_tex, err);
        if (r != ENG_OK)
            return r;
    }

    /* Composite and display transform; indirect light × occlusion where a material has an
     * occlusion texture (glTF §3.9.3: it applies to indirect light only). */
    int occluded = 0;
    for (uint32_t i = 0; i < e->scene->material_count; i++)
        occluded |= e->scene->materials[i].occlusion_tex.texture >= 0;
    pass_composite_set_occlusion(e->composite, occluded ? gb->color[5] : 0);
    t0 = now_ms();
    const glu_target *comp =
        pass_composite_run(e->composite, direct->color[0], indirect_tex, specular_tex, emission_tex,
                           translucent_tex, &e->settings);
    glFinish();
    if (e->settings.exposure_auto && !e->exposure_resolved && frame == 0)
        comp = meter_exposure(e, gb, comp, direct->color[0], indirect_tex, specular_tex, emission_tex,
                              translucent_tex);
    add_time(e, "composite", now_ms() - t0);
    e->stats.exposure_auto = e->settings.exposure_auto;
    e->stats.exposure = e->settings.exposure;
    if (announce_outputs(e, frame, pass_composite_outputs, comp, NULL, 0, NULL, NULL, name))
        return eng_fail(err, ENG_ERR_ABORTED, "frame %d: capture failed in the composite pass", frame);

    GLenum gle = glGetError();
    if (gle != GL_NO_ERROR)
        return eng_fail(err, ENG_ERR_GL, "%s: frame %d: GL error 0x%x after the composite pass", e->seq->path,
                        frame, gle);
    add_time(e, "readback", e->readback_ms);
    e->next_frame = frame + 1;
    e->stats.history_from = history_from(e, frame);
    for (int i = 0; i < e->listener_count && !e->silent; i++)
        if (e->listeners[i].frame_end && e->listeners[i].frame_end(e->listeners[i].user, &e->stats) != 0)
            return eng_fail(err, ENG_ERR_ABORTED, "frame %d: a listener failed to finish the frame", frame);
    return ENG_OK;
}

void eng_pose(eng_engine *e, int frame, const eng_frame_scene **fs, const eng_rt **rt)
{
    pose_frame(e, frame);
    rt_update(e->rt, &e->fs);
    *fs = &e->fs;
    *rt = e->rt;
}

const eng_settings *eng_settings_of(const eng_engine *e) { return &e->settings; }

void eng_image_size(const eng_engine *e, int *width, int *height)
{
    *width = e->width;
    *height = e->height;
}

int eng_occluded(eng_engine *e, const float a[3], const float b[3])
{
    if (!e->fs.draw_count)
        return 0;
    if (!e->stats.pass_count) { /* nothing rendered yet: pose at t = 0 */
        pose_frame(e, 0);
        rt_update(e->rt, &e->fs);
    }
    return rt_occluded(e->rt, a, b);
}

eng_result eng_frame_trace_inputs(eng_engine *e, int frame, eng_trace_inputs *out, eng_error *err)
{
    memset(out, 0, sizeof *out);
    if (frame < 0 || frame >= e->seq->frame_count)
        return eng_fail(err, ENG_ERR_INVALID, "%s: frame %d outside 0..%d", e->seq->path, frame, e->seq->frame_count - 1);
    if (!e->method)
        return eng_fail(err, ENG_ERR_INVALID, "%s: no photon trace with \"indirect\": \"none\"", e->seq->path);
    pose_frame(e, frame);
    rt_update(e->rt, &e->fs);
    eng_rmap_frame rf;
    rmap_frame(&e->settings, frame, &rf);
    eng_result r = light_passes(e, frame, &rf, err);
    if (r != ENG_OK)
        return r;
    out->rt = e->rt;
    out->fs = &e->fs;
    out->rm = &e->rmaps;
    out->in = e->bounce;
    out->count = e->bounce_count;
    eng_trace_settings ts = {e->settings.bounces, e->settings.threads, rf.salt, rf.stratified,
                             {rf.offset[0], rf.offset[1], rf.offset[2], rf.offset[3]},
                             2.0f * e->settings.kernel_radius};
    out->settings = ts;
    return ENG_OK;
}

int eng_gl_backend_known(const char *name)
{
    return glctx_backend_known(name);
}

void eng_pin_determinism(int threads)
{
    glctx_pin_determinism(threads);
}

const char *const *eng_determinism_info(void)
{
    return glctx_determinism_info();
}
