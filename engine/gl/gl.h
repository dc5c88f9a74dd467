/* gl.h — the GL room's face: the context (one backend per file behind glctx_backend.h, found
 * by name), shader programs from the embedded GLSL of shaders/, render targets and fullscreen
 * passes, read-back into CPU images and uploads from them. Every GL function is a pointer loaded
 * from the context's backend (glctx.c). */
#ifndef ISPM_GL_H
#define ISPM_GL_H

#include "gl_loader.h"

#include "eng_core.h"

/* ---------------------------------------------------------------- GL helpers (glutil.c) */

/* Compiles and links vertex + fragment shaders from engine/gl/shaders/<name>; the error names
 * the shader file and carries the driver's log (flattened to one line). */
eng_result glu_program(const char *vert_name, const char *frag_name, GLuint *out, eng_error *err);
/* The same with lines of preprocessor definitions (e.g. "#define X\n") inserted into the
 * fragment shader after its #version line (shader variants from one source file). */
eng_result glu_program_defines(const char *vert_name, const char *frag_name, const char *frag_defines, GLuint *out,
                               eng_error *err);
/* A compute program from one embedded shader (GL 4.3+; llvmpipe has 4.5). */
eng_result glu_compute_program(const char *name, GLuint *out, eng_error *err);

/* A framebuffer with `count` RGBA32F colour attachments of w×h and a 32F depth buffer.
 * layers > 0 makes each colour attachment a 2D array texture of that many layers (attach
 * one layer at a time with glu_target_bind_layer). */
typedef struct glu_target {
    GLuint fbo;
    GLuint color[8];
    GLuint depth;
    int count, width, height, layers;
} glu_target;

eng_result glu_target_create(glu_target *t, int count, int width, int height, int layers, eng_error *err);
void glu_target_destroy(glu_target *t);
void glu_target_bind_layer(glu_target *t, int layer);

/* Reads attachment `index` (layer `layer` for array targets) as RGBA float, converts to top
 * row first and keeps `channels` of the 4 components listed in `pick` (e.g. {0,1,2}) into
 * out (w*h*channels floats, interleaved). */
void glu_read(const glu_target *t, int index, int layer, int channels, const int *pick, float *out);

GLuint glu_fullscreen_vao(void); /* an empty VAO: the fullscreen triangle is made in the VS */

/* A fullscreen fragment pass: fullscreen.vert.glsl + a fragment shader, `count` RGBA32F
 * targets of width×height, and the empty VAO it draws with. */
typedef struct glu_pass {
    glu_target target;
    GLuint program, vao;
} glu_pass;

eng_result glu_pass_create(glu_pass *p, const char *frag_name, int count, int width, int height, eng_error *err);
void glu_pass_destroy(glu_pass *p);
/* Draws the fullscreen triangle into p's target with p's program (bound by the caller). */
void glu_pass_draw(const glu_pass *p);
/* Same into another target of the same kind (ping-pong, per-iteration targets). */
void glu_pass_draw_to(const glu_pass *p, const glu_target *t);

/* ---------------------------------------------------------------- GL context (glctx.c) */

typedef struct eng_glctx eng_glctx;
/* A context from backend (NULL: ENG_GL_DEFAULT), made current; use_device: EGL device
 * `device` (--gl-device). Loads every GL function through the backend. */
eng_result glctx_create_on(const char *backend, int use_device, int device, eng_glctx **out, eng_error *err);
eng_result glctx_create(eng_glctx **out, eng_error *err); /* the default backend */
const char *glctx_backend_name(const eng_glctx *c);
const char *glctx_where(const eng_glctx *c);
void glctx_destroy(eng_glctx *c);
const char *glctx_version(const eng_glctx *c);
const char *glctx_renderer(const eng_glctx *c);
/* ---------------------------------------------------------------- CPU images (readback.c) */

/* A target filled from the CPU (the CPU indirect methods, specular, translucency): 1 or 2 RGBA32F attachments of w×h. */
typedef struct glu_cpu_target {
    glu_target target;
    float *upload; /* w×h×4 scratch for flipping rows */
} glu_cpu_target;
eng_result glu_cpu_target_create(glu_cpu_target *t, int width, int height, int irradiance, eng_error *err);
void glu_cpu_target_destroy(glu_cpu_target *t);
/* Uploads w×h RGBA (top row first) into attachment `index`. */
void glu_cpu_target_upload(glu_cpu_target *t, int index, const float *rgba);

/* The eye G-buffer (pass_gbuffer's layout) read back: top row first. */
typedef struct glu_gbuffer {
    int width, height;
    float *position; /* 4 per pixel, w = coverage */
    float *normal;   /* 3 */
    float *albedo;   /* 3 */
    float *material; /* 4: roughness, metallic, transmission, ior */
} glu_gbuffer;
void glu_gbuffer_read(const glu_target *gb, glu_gbuffer *out); /* (re)allocates out's arrays */
void glu_gbuffer_free(glu_gbuffer *g);

/* Uploads w×h scales (top row first) into the R32F texture *tex (created on first use, with
 * *rows its w×h upload scratch): the u_pixel_scale of shaders/pixel_scale.glsl. */
void pixel_scale_upload(GLuint *tex, float **rows, int w, int h, const float *scale);

/* The backends' names, and the process settings that pin llvmpipe's and Embree's SIMD width
 * (eng.h: eng_pin_determinism, eng_determinism_info, eng_gl_backend_known). */
int glctx_backend_known(const char *name);
void glctx_pin_determinism(int threads);
const char *const *glctx_determinism_info(void);

#endif
