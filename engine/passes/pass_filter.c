/* pass_filter.c — the reconstruction filters between the photon splat and the composite
 * (DESIGN.md step 7), each a fullscreen fragment pass on RGBA32F targets:
 *   upsample  joint bilateral upsampling of subsampled irradiance, one ×2 level per run
 *             (ISPM 003_… §5.2, Fig. 12; multi-level as in 004_… §6), shaders/upsample.frag.glsl
 *   temporal  exponential moving average with reprojected history and geometric rejection
 *             (002_… §7.2, Eq. 7.3–7.4), shaders/temporal.frag.glsl
 *   atrous    edge-avoiding À-Trous wavelet with variance-clipped detail coefficients
 *             (002_… §7.3, Eq. 7.5–7.8), shaders/atrous.frag.glsl
 *   resolve   the BSDF applied to the filtered irradiance (002_… §7.4, Eq. 7.9),
 *             shaders/resolve.frag.glsl
 * The edge-stopping weights they share (002 Eq. 7.1–7.2) are in shaders/edge_stop.glsl.
 * Each pass owns its program and targets; the temporal pass also owns its history (previous
 * result, previous G-buffer normal and depth), which makes it the one stateful pass: the
 * engine renders frames in order when it is on.
 *
 * Determinism: every output texel is computed by one fragment from fixed texel fetches in a
 * fixed order, so the results do not depend on llvmpipe's thread count. */
#include "passes.h"

#include <stdlib.h>

static void bind_tex(int unit, GLuint tex)
{
    glActiveTexture(GL_TEXTURE0 + (GLenum)unit);
    glBindTexture(GL_TEXTURE_2D, tex);
}

static void set_units(GLuint prog, const char *const *names, int count)
{
    glUseProgram(prog);
    for (int i = 0; i < count; i++)
        glUniform1i(glGetUniformLocation(prog, names[i]), i);
}

/* ---------------------------------------------------------------- upsample */

struct pass_upsample {
    glu_pass pass;
};

static const char *const UPSAMPLE_UNITS[] = {"u_lo_irradiance", "u_lo_glossy", "u_lo_normal", "u_lo_misc",
                                             "u_hi_normal", "u_hi_misc"};

eng_result pass_upsample_create(int width, int height, pass_upsample **out, eng_error *err)
{
    *out = NULL;
    pass_upsample *p = calloc(1, sizeof *p);
    if (!p)
        return eng_fail(err, ENG_ERR_NOMEM, "upsample: out of memory");
    eng_result r = glu_pass_create(&p->pass, "upsample.frag.glsl", 2, width, height, err);
    if (r != ENG_OK) {
        free(p);
        return r;
    }
    set_units(p->pass.program, UPSAMPLE_UNITS, 6);
    *out = p;
    return ENG_OK;
}

/* <k>: the level upsampled to (0 = full size). */
const pass_output pass_upsample_outputs[] = {
    {.name = "upsample.level<k>", .attachment = 0, .pick = {0, 1, 2}, .channels = {"R", "G", "B"}},
    {0},
};

const glu_target *pass_upsample_run(pass_upsample *p, const glu_target *lo_gb, GLuint lo_irradiance,
                                    GLuint lo_glossy, const glu_target *hi_gb)
{
    glUseProgram(p->pass.program);
    bind_tex(0, lo_irradiance);
    bind_tex(1, lo_glossy);
    bind_tex(2, lo_gb->color[1]);
    bind_tex(3, lo_gb->color[4]);
    bind_tex(4, hi_gb->color[1]);
    bind_tex(5, hi_gb->color[4]);
    glu_pass_draw(&p->pass);
    return &p->pass.target;
}

void pass_upsample_destroy(pass_upsample *p)
{
    if (!p)
        return;
    glu_pass_destroy(&p->pass);
    free(p);
}

/* ---------------------------------------------------------------- temporal */

struct pass_temporal {
    glu_pass pass;        /* program; its target is ping-pong buffer 0 */
    glu_target other;     /* ping-pong buffer 1 */
    glu_target prev_gb;   /* 0 = previous normal (+ previous-frame depth), 1 = previous misc */
    int current;          /* which buffer the last run wrote; -1 = no history */
};

static const char *const TEMPORAL_UNITS[] = {"u_irradiance", "u_normal", "u_misc", "u_prev_result",
                                             "u_prev_normal", "u_prev_misc"};

eng_result pass_temporal_create(int width, int height, pass_temporal **out, eng_error *err)
{
    *out = NULL;
    pass_temporal *p = calloc(1, sizeof *p);
    if (!p)
        return eng_fail(err, ENG_ERR_NOMEM, "temporal: out of memory");
    eng_result r = glu_pass_create(&p->pass, "temporal.frag.glsl", 2, width, height, err);
    if (r == ENG_OK)
        r = glu_target_create(&p->other, 2, width, height, 0, err);
    if (r == ENG_OK)
        r = glu_target_create(&p->prev_gb, 2, width, height, 0, err);
    if (r != ENG_OK) {
        pass_temporal_destroy(p);
        return r;
    }
    set_units(p->pass.program, TEMPORAL_UNITS, 6);
    p->current = -1;
    *out = p;
    return ENG_OK;
}

void pass_temporal_reset(pass_temporal *p) { p->current = -1; }

const pass_output pass_temporal_outputs[] = {
    {.name = "temporal.history", .attachment = 1, .pick = {0, 1, 2}, .channels = {"R", "G", "B"}},
    {.name = "temporal.alpha", .attachment = 0, .pick = {3}, .channels = {"Y"}},
    {.name = "temporal.result", .attachment = 0, .pick = {0, 1, 2}, .channels = {"R", "G", "B"}},
    {0},
};

const glu_target *pass_temporal_run(pass_temporal *p, const glu_target *gb, GLuint irradiance, float alpha)
{
    const glu_target *bufs[2] = {&p->pass.target, &p->other};
    int has_history = p->current >= 0;
    int next = has_history ? 1 - p->current : 0;
    GLuint g = p->pass.program;
    glUseProgram(g);
    glUniform1i(glGetUniformLocation(g, "u_has_history"), has_history);
    glUniform1f(glGetUniformLocation(g, "u_alpha"), alpha);
    bind_tex(0, irradiance);
    bind_tex(1, gb->color[1]);
    bind_tex(2, gb->color[4]);
    bind_tex(3, has_history ? bufs[p->current]->color[0] : 0);
    bind_tex(4, p->prev_gb.color[0]);
    bind_tex(5, p->prev_gb.color[1]);
    glu_pass_draw_to(&p->pass, bufs[next]);
    /* This frame's normal and depth become the next frame's "previous" ones. */
    glCopyImageSubData(gb->color[1], GL_TEXTURE_2D, 0, 0, 0, 0, p->prev_gb.color[0], GL_TEXTURE_2D, 0, 0, 0, 0,
                       gb->width, gb->height, 1);
    glCopyImageSubData(gb->color[4], GL_TEXTURE_2D, 0, 0, 0, 0, p->prev_gb.color[1], GL_TEXTURE_2D, 0, 0, 0, 0,
                       gb->width, gb->height, 1);
    p->current = next;
    return bufs[next];
}

void pass_temporal_destroy(pass_temporal *p)
{
    if (!p)
        return;
    glu_pass_destroy(&p->pass);
    glu_target_destroy(&p->other);
    glu_target_destroy(&p->prev_gb);
    free(p);
}

/* ---------------------------------------------------------------- À-Trous */

#define ATROUS_MAX 8

struct pass_atrous {
    glu_pass pass; /* program; its target is iteration 0's */
    glu_target level[ATROUS_MAX];
    int iterations;
};

static const char *const ATROUS_UNITS[] = {"u_scale", "u_detail_sum", "u_normal", "u_misc"};

eng_result pass_atrous_create(int width, int height, int iterations, pass_atrous **out, eng_error *err)
{
    *out = NULL;
    if (iterations < 1 || iterations > ATROUS_MAX)
        return eng_fail(err, ENG_ERR_INVALID, "atrous: %d iterations (1..%d)", iterations, ATROUS_MAX);
    pass_atrous *p = calloc(1, sizeof *p);
    if (!p)
        return eng_fail(err, ENG_ERR_NOMEM, "atrous: out of memory");
    p->iterations = iterations;
    eng_result r = glu_pass_create(&p->pass, "atrous.frag.glsl", 4, width, height, err);
    p->level[0] = p->pass.target;
    for (int i = 1; i < iterations && r == ENG_OK; i++)
        r = glu_target_create(&p->level[i], 4, width, height, 0, err);
    if (r != ENG_OK) {
        pass_atrous_destroy(p);
        return r;
    }
    set_units(p->pass.program, ATROUS_UNITS, 4);
    *out = p;
    return ENG_OK;
}

/* Per iteration i (<k>) from its target: S_{i+1} and the kept detail D'_i. */
const pass_output pass_atrous_outputs[] = {
    {.name = "atrous.scale<k>", .attachment = 0, .pick = {0, 1, 2}, .channels = {"R", "G", "B"}, .level_offset = 1},
    {.name = "atrous.detail<k>", .attachment = 1, .pick = {0, 1, 2}, .channels = {"R", "G", "B"}},
    {0},
};

/* From the last iteration's target. */
const pass_output pass_atrous_result_outputs[] = {
    {.name = "atrous.result", .attachment = 3, .pick = {0, 1, 2}, .channels = {"R", "G", "B"}},
    {0},
};

const glu_target *pass_atrous_run(pass_atrous *p, const glu_target *gb, GLuint irradiance,
                                  eng_atrous_detail detail, float gamma)
{
    GLuint g = p->pass.program;
    glUseProgram(g);
    int mode = detail == ENG_DETAIL_NONE ? 1 : detail == ENG_DETAIL_ALL ? 2 : 0;
    glUniform1i(glGetUniformLocation(g, "u_detail"), mode);
    glUniform1f(glGetUniformLocation(g, "u_gamma"), gamma);
    for (int i = 0; i < p->iterations; i++) {
        glUseProgram(g);
        glUniform1i(glGetUniformLocation(g, "u_step"), 1 << i);
        glUniform1i(glGetUniformLocation(g, "u_first"), i == 0);
        bind_tex(0, i == 0 ? irradiance : p->level[i - 1].color[0]);
        bind_tex(1, i == 0 ? irradiance : p->level[i - 1].color[2]);
        bind_tex(2, gb->color[1]);
        bind_tex(3, gb->color[4]);
        glu_pass_draw_to(&p->pass, &p->level[i]);
    }
    return p->level;
}

void pass_atrous_destroy(pass_atrous *p)
{
    if (!p)
        return;
    for (int i = 1; i < p->iterations; i++)
        glu_target_destroy(&p->level[i]);
    glu_pass_destroy(&p->pass); /* owns level[0] */
    free(p);
}

/* ---------------------------------------------------------------- resolve */

struct pass_resolve {
    glu_pass pass;
};

static const char *const RESOLVE_UNITS[] = {"u_irradiance", "u_glossy", "u_albedo", "u_material", "u_normal"};

eng_result pass_resolve_create(int width, int height, pass_resolve **out, eng_error *err)
{
    *out = NULL;
    pass_resolve *p = calloc(1, sizeof *p);
    if (!p)
        return eng_fail(err, ENG_ERR_NOMEM, "resolve: out of memory");
    eng_result r = glu_pass_create(&p->pass, "resolve.frag.glsl", 1, width, height, err);
    if (r != ENG_OK) {
        free(p);
        return r;
    }
    set_units(p->pass.program, RESOLVE_UNITS, 5);
    *out = p;
    return ENG_OK;
}

const pass_output pass_resolve_outputs[] = {
    {.name = "indirect.radiance", .attachment = 0, .pick = {0, 1, 2}, .channels = {"R", "G", "B"}},
    {0},
};

const glu_target *pass_resolve_run(pass_resolve *p, const glu_target *gb, GLuint irradiance, GLuint glossy)
{
    glUseProgram(p->pass.program);
    bind_tex(0, irradiance);
    bind_tex(1, glossy);
    bind_tex(2, gb->color[2]);
    bind_tex(3, gb->color[3]);
    bind_tex(4, gb->color[1]);
    glu_pass_draw(&p->pass);
    return &p->pass.target;
}

void pass_resolve_destroy(pass_resolve *p)
{
    if (!p)
        return;
    glu_pass_destroy(&p->pass);
    free(p);
}
