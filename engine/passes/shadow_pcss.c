/* shadow_pcss.c — soft shadows of lights with a size (shadow.h "pcss"; 001 §3.4), in one of
 * two ways by the setting pcss_blocker (shaders/shadow_pcss.glsl does the lookups):
 *
 *   map   runs the blocker search (shaders/blocker.frag.glsl) over every face of the light's
 *         shadow map into a blocker map of the same layout at half its resolution,
 *         `shadow.light<i>[.face<f>].blocker`; the direct pass turns it into a penumbra width
 *         (001 Eq. 5) and filters the shadow map over that width. One depth per receiver: where
 *         an occluder's near and far edges both shape a penumbra (a box standing on the floor)
 *         the width follows their average;
 *   rays  needs no map of its own: the direct pass marches rays from the receiver to points of
 *         the light's disc through the shadow map, and a ray is blocked where it crosses a
 *         stored surface (shadow_rays_cpu below is the same march on the CPU).
 */
#include "shadow.h"

#include <math.h>
#include <stdlib.h>

#define PCSS_BLOCKER_TAPS 16      /* = BLOCKER_TAPS of blocker.frag.glsl */
#define PCSS_BLOCKER_MAX 48.0f    /* = BLOCKER_MAX_RADIUS */
#define PCSS_GOLDEN_ANGLE 2.39996322972865332
#define PCSS_RAY_SAMPLES 16       /* = PCSS_RAY_SAMPLES of shadow_pcss.glsl */
#define PCSS_RAY_STEP 1.5f        /* = PCSS_RAY_STEP */
#define PCSS_RAY_REACH 48.0f      /* = PCSS_RAY_REACH */
#define PCSS_RAY_HIT 8.0f         /* = PCSS_RAY_HIT */
#define PCSS_RAY_TOL 2.0f         /* = PCSS_RAY_TOL */

typedef struct pcss_state {
    int size;         /* of the shadow maps; the blocker maps are (size + 1) / 2 */
    int rays;         /* pcss_blocker "rays": no blocker pass */
    uint32_t light_count;
    glu_target *maps; /* per light */
    GLuint program, vao;
} pcss_state;

static void pcss_destroy(void *state)
{
    pcss_state *p = state;
    if (!p)
        return;
    for (uint32_t i = 0; i < p->light_count; i++)
        glu_target_destroy(&p->maps[i]);
    free(p->maps);
    if (p->vao)
        glDeleteVertexArrays(1, &p->vao);
    if (p->program)
        glDeleteProgram(p->program);
    free(p);
}

static eng_result pcss_create(const eng_settings *s, uint32_t light_count, void **state, eng_error *err)
{
    *state = NULL;
    pcss_state *p = calloc(1, sizeof *p);
    if (!p)
        return eng_fail(err, ENG_ERR_NOMEM, "pcss: out of memory");
    p->size = s->shadow_map_size;
    p->rays = s->pcss_blocker == ENG_PCSS_RAYS;
    p->light_count = light_count;
    p->maps = calloc(light_count ? light_count : 1, sizeof *p->maps);
    if (!p->maps) {
        free(p);
        return eng_fail(err, ENG_ERR_NOMEM, "pcss: out of memory");
    }
    if (p->rays) {
        *state = p;
        return ENG_OK;
    }
    eng_result r = glu_program("fullscreen.vert.glsl", "blocker.frag.glsl", &p->program, err);
    if (r != ENG_OK) {
        pcss_destroy(p);
        return r;
    }
    p->vao = glu_fullscreen_vao();
    glUseProgram(p->program);
    glUniform1i(glGetUniformLocation(p->program, "u_shadow"), 0);
    *state = p;
    return ENG_OK;
}

/* The nearest distance from the light an occluder can have: just outside the emitter. */
static float pcss_near(const eng_light_pose *l)
{
    return l->type == SCN_LIGHT_DIRECTIONAL ? 0.0f : fmaxf(1.5f * l->radius, 0.05f);
}

static const glu_target *pcss_run(void *state, const eng_light_pose *l, const shadow_map *sm, uint32_t light,
                                  int *failed)
{
    pcss_state *p = state;
    *failed = 0;
    if (p->rays)
        return NULL;
    glu_target *t = &p->maps[light];
    if (t->fbo && t->layers != sm->faces)
        glu_target_destroy(t);
    if (!t->fbo) {
        eng_error e;
        int half = (p->size + 1) / 2;
        if (glu_target_create(t, 1, half, half, sm->faces, &e) != ENG_OK) {
            *failed = 1;
            return NULL;
        }
    }
    GLuint g = p->program;
    int directional = l->type == SCN_LIGHT_DIRECTIONAL;
    glUseProgram(g);
    glUniform1i(glGetUniformLocation(g, "u_size"), p->size);
    glUniform1i(glGetUniformLocation(g, "u_directional"), directional);
    glUniform1f(glGetUniformLocation(g, "u_radius"), directional ? tanf(l->radius) : l->radius);
    glUniform1f(glGetUniformLocation(g, "u_texel"), 2.0f * light_view_extent(l, sm) / (float)p->size);
    glUniform1f(glGetUniformLocation(g, "u_near"), pcss_near(l));
    glUniform1f(glGetUniformLocation(g, "u_far"), sm->far_value);
    glActiveTexture(GL_TEXTURE0);
    glBindTexture(GL_TEXTURE_2D_ARRAY, sm->target.color[0]);
    glViewport(0, 0, t->width, t->height);
    glDisable(GL_DEPTH_TEST);
    glBindVertexArray(p->vao);
    for (int f = 0; f < sm->faces; f++) {
        glu_target_bind_layer(t, f);
        glUniform1i(glGetUniformLocation(g, "u_face"), f);
        glDrawArrays(GL_TRIANGLES, 0, 3);
    }
    glBindVertexArray(0);
    glBindFramebuffer(GL_FRAMEBUFFER, 0);
    return t;
}

/* Light <i>'s blocker map, per face: the average occluder depth. */
static const pass_output pcss_outputs[] = {
    {.name = "shadow.light<i>[.face<f>].blocker", .attachment = 0, .pick = {0}, .channels = {"Z"}},
    {0},
};

const shadow_method shadow_pcss_method = {
    .name = "pcss",
    .outputs = pcss_outputs,
    .pass = "softshadow",
    .create = pcss_create,
    .run = pcss_run,
    .destroy = pcss_destroy,
};

float shadow_penumbra_texels(int directional, float r, float receiver, float blocker, float texel)
{
    /* 001 Eq. 5: R_g = L·d/(D−d), d = receiver − blocker, D − d = blocker; divided by the
     * receiver distance (the map's perspective) and the texel size. */
    if (directional)
        return r * (receiver - blocker) / texel;
    return r * (receiver - blocker) / (receiver * blocker * texel);
}

float shadow_search_texels(int directional, float r, float z, float near, float texel)
{
    if (directional)
        return r * z / texel;
    return r * fmaxf(z - near, 0.0f) / (z * near * texel);
}

static float fetch(const float *map, int size, int x, int y)
{
    x = x < 0 ? 0 : x >= size ? size - 1 : x;
    y = y < 0 ? 0 : y >= size ? size - 1 : y;
    return map[(size_t)y * (size_t)size + (size_t)x];
}

static float smaller(float a, float b)
{
    return fabsf(a) < fabsf(b) ? a : b;
}

float shadow_blocker_cpu(const float *map, int size, float far_value, int directional, float r, float near,
                         float texel, int hx, int hy)
{
    /* The receiver: the farthest non-empty texel of the 2×2 block (blocker.frag.glsl). */
    int x = 2 * hx, y = 2 * hy;
    float z = -1.0f;
    for (int k = 0; k < 4; k++) {
        int tx = 2 * hx + (k & 1), ty = 2 * hy + (k >> 1);
        float v = fetch(map, size, tx, ty);
        if (v < far_value && v > z) {
            z = v;
            x = tx < size ? tx : size - 1;
            y = ty < size ? ty : size - 1;
        }
    }
    if (z < 0.0f)
        return 0.0f;
    float sx = smaller(fetch(map, size, x + 1, y) - z, z - fetch(map, size, x - 1, y));
    float sy = smaller(fetch(map, size, x, y + 1) - z, z - fetch(map, size, x, y - 1));
    float radius = shadow_search_texels(directional, r, z, near, texel);
    radius = radius < 1.0f ? 1.0f : radius > PCSS_BLOCKER_MAX ? PCSS_BLOCKER_MAX : radius;
    float tol = 3.0f * (directional ? texel : texel * z) + 0.002f;
    float sum = 0.0f, count = 0.0f;
    for (int k = 0; k < PCSS_BLOCKER_TAPS; k++) {
        float rr = radius * sqrtf(((float)k + 0.5f) / (float)PCSS_BLOCKER_TAPS);
        float a = (float)(k * PCSS_GOLDEN_ANGLE);
        float ox = roundf(rr * cosf(a)), oy = roundf(rr * sinf(a));
        int tx = x + (int)ox, ty = y + (int)oy;
        if (tx < 0 || ty < 0 || tx >= size || ty >= size)
            continue; /* beyond the face: no continuation of the receiver to compare with */
        float s = map[(size_t)ty * (size_t)size + (size_t)tx];
        if (s + tol < z + sx * ox + sy * oy) {
            sum += s;
            count += 1.0f;
        }
    }
    return count > 0.0f ? sum / count : 0.0f;
}

/* One point of the ortho march: the stored value at lateral position (x, y) (texels) and the
 * point's own depth v; its tolerance, as shadow_pcss.glsl's pcss_ray_map for the ortho box. */
typedef struct ray_at {
    float stored, value, tol;
} ray_at;

static ray_at ray_map(const float *map, int size, float texel, float bias, float x, float y, float v)
{
    ray_at m = {fetch(map, size, (int)floorf(x), (int)floorf(y)), v, bias + PCSS_RAY_TOL * texel};
    return m;
}

static int ray_behind(ray_at m)
{
    return m.value > m.stored + m.tol;
}

float shadow_rays_cpu(const float *map, int size, float r, float texel, float bias, float x, float y, float value)
{
    ray_at m0 = ray_map(map, size, texel, bias, x, y, value);
    float reach = fminf(PCSS_RAY_REACH * texel / r, value);
    float g = 0.06711056f * floorf(x) + 0.00583715f * floorf(y);
    g = 52.9829189f * (g - floorf(g));
    float turn = 6.28318530717958648f * (g - floorf(g));
    int lit = 0;
    for (int k = 0; k < PCSS_RAY_SAMPLES; k++) {
        float rho = r * sqrtf(((float)k + 0.5f) / (float)PCSS_RAY_SAMPLES);
        float a = (float)(k * PCSS_GOLDEN_ANGLE) + turn;
        /* Lateral texels per unit of depth travelled toward this point of the light. */
        float dx = rho * cosf(a) / texel, dy = rho * sinf(a) / texel;
        int blocked = 0;
        float s_prev = 0.0f;
        ray_at m_prev = m0;
        int steps = (int)ceilf(reach * rho / texel / PCSS_RAY_STEP);
        steps = steps < 1 ? 1 : steps;
        for (int j = 1; j <= steps && !blocked; j++) {
            float s = reach * (float)j / (float)steps;
            ray_at m = ray_map(map, size, texel, bias, x + s * dx, y + s * dy, value - s);
            /* The stored depths at either end that the ray's depth passes over this step: is
             * that surface where the ray is at that depth? */
            for (int e = 0; e < 2 && !blocked; e++) {
                float c = e == 0 ? m_prev.stored : m.stored;
                if (c >= m.value && c < m_prev.value - (j == 1 ? m_prev.tol : 0.0f)) {
                    float sc = s_prev + (s - s_prev) * (m_prev.value - c) / (m_prev.value - m.value);
                    ray_at mc = ray_map(map, size, texel, bias, x + sc * dx, y + sc * dy, value - sc);
                    blocked = fabsf(mc.value - mc.stored) <= PCSS_RAY_HIT * mc.tol;
                }
            }
            s_prev = s;
            m_prev = m;
        }
        blocked = blocked || ray_behind(m_prev);
        lit += !blocked;
    }
    return (float)lit / (float)PCSS_RAY_SAMPLES;
}
