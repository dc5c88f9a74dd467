/* test_glctx.c — the GL context backends (engine/glctx*.c): choosing a backend by name, the
 * errors for an unknown one and for an EGL device this machine does not have, GL loaded
 * through each backend, and "same llvmpipe, same bits": a fragment shader of transcendental
 * functions rendered into a float framebuffer object through OSMesa and through Mesa's EGL
 * (surfaceless and EGL device 0) gives the same bytes under the pinned llvmpipe settings.
 * (EGL missing altogether is tested by tests/e2e_egl.sh, which can hide glvnd's vendors.) */
#include "gl.h"

#include <check.h>
#include <stdio.h>
#include <stdlib.h>
#include <math.h>
#include <string.h>

#define S 16

START_TEST(backend_names)
{
    ck_assert(glctx_backend_known("osmesa"));
    ck_assert(glctx_backend_known("egl"));
    ck_assert(!glctx_backend_known("OSMesa"));
    ck_assert(!glctx_backend_known("vulkan"));
    ck_assert(!glctx_backend_known(""));
    ck_assert(!glctx_backend_known(NULL));
}
END_TEST

START_TEST(unknown_backend_is_one_line_invalid)
{
    eng_glctx *c = (eng_glctx *)1;
    eng_error err = {{0}};
    ck_assert_int_eq(glctx_create_on("vulkan", 0, 0, &c, &err), ENG_ERR_INVALID);
    ck_assert_ptr_null(c);
    ck_assert_msg(strstr(err.msg, "\"vulkan\"") && strstr(err.msg, "osmesa, egl"), "%s", err.msg);
    ck_assert_ptr_null(strchr(err.msg, '\n'));
}
END_TEST

START_TEST(egl_device_out_of_range_is_invalid)
{
    glctx_pin_determinism(2);
    eng_glctx *c = NULL;
    eng_error err = {{0}};
    ck_assert_int_eq(glctx_create_on("egl", 1, 999, &c, &err), ENG_ERR_INVALID);
    ck_assert_ptr_null(c);
    ck_assert_msg(strstr(err.msg, "--gl-device 999") && strstr(err.msg, "EGL device"), "%s", err.msg);
    ck_assert_ptr_null(strchr(err.msg, '\n'));
}
END_TEST

static GLuint shader(GLenum type, const char *src)
{
    GLuint s = glCreateShader(type);
    glShaderSource(s, 1, &src, NULL);
    glCompileShader(s);
    GLint ok = 0;
    glGetShaderiv(s, GL_COMPILE_STATUS, &ok);
    ck_assert_msg(ok, "shader does not compile");
    return s;
}

/* Renders S×S pixels of transcendental functions into an RGBA32F FBO; out gets the floats. */
static void render_probe(float *out)
{
    static const char *vs = "#version 450 core\n"
                            "void main() { vec2 p = vec2(gl_VertexID == 1 ? 3.0 : -1.0, gl_VertexID == 2 ? 3.0 : -1.0);\n"
                            "  gl_Position = vec4(p, 0.0, 1.0); }\n";
    static const char *fs = "#version 450 core\nout vec4 o;\n"
                            "void main() { vec2 p = gl_FragCoord.xy * 0.37;\n"
                            "  o = vec4(sin(p.x) * exp(p.y * 0.1), inversesqrt(p.x + 1.0), pow(p.y + 0.5, 1.7),\n"
                            "           atan(p.y, p.x + 0.1) + log2(p.x * p.y + 1.0)); }\n";
    GLuint prog = glCreateProgram();
    GLuint v = shader(GL_VERTEX_SHADER, vs), f = shader(GL_FRAGMENT_SHADER, fs);
    glAttachShader(prog, v);
    glAttachShader(prog, f);
    glLinkProgram(prog);
    GLint ok = 0;
    glGetProgramiv(prog, GL_LINK_STATUS, &ok);
    ck_assert(ok);
    GLuint tex, fbo, vao;
    glGenTextures(1, &tex);
    glBindTexture(GL_TEXTURE_2D, tex);
    glTexStorage2D(GL_TEXTURE_2D, 1, GL_RGBA32F, S, S);
    glGenFramebuffers(1, &fbo);
    glBindFramebuffer(GL_FRAMEBUFFER, fbo);
    glFramebufferTexture2D(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_TEXTURE_2D, tex, 0);
    ck_assert_int_eq(glCheckFramebufferStatus(GL_FRAMEBUFFER), GL_FRAMEBUFFER_COMPLETE);
    glGenVertexArrays(1, &vao);
    glBindVertexArray(vao);
    glViewport(0, 0, S, S);
    glUseProgram(prog);
    glDrawArrays(GL_TRIANGLES, 0, 3);
    glReadPixels(0, 0, S, S, GL_RGBA, GL_FLOAT, out);
    ck_assert_int_eq(glGetError(), GL_NO_ERROR);
    glDeleteVertexArrays(1, &vao);
    glDeleteFramebuffers(1, &fbo);
    glDeleteTextures(1, &tex);
    glDeleteProgram(prog);
    glDeleteShader(v);
    glDeleteShader(f);
}

/* Opens backend (device: -1 none), checks what it reports, renders the probe, closes it. */
static void probe(const char *backend, int device, const char *where, float *out, char *renderer)
{
    eng_glctx *c = NULL;
    eng_error err = {{0}};
    ck_assert_msg(glctx_create_on(backend, device >= 0, device, &c, &err) == ENG_OK, "%s: %s", backend, err.msg);
    ck_assert_str_eq(glctx_backend_name(c), backend);
    ck_assert_msg(strncmp(glctx_where(c), where, strlen(where)) == 0, "%s", glctx_where(c));
    int major = 0, minor = 0;
    ck_assert_msg(sscanf(glctx_version(c), "%d.%d", &major, &minor) == 2 && (major > 4 || (major == 4 && minor >= 5)),
                  "GL 4.5 or later: %s", glctx_version(c));
    snprintf(renderer, 128, "%s", glctx_renderer(c));
    ck_assert_ptr_nonnull(glDispatchCompute); /* loaded through the backend */
    render_probe(out);
    glctx_destroy(c);
}

START_TEST(osmesa_and_egl_give_the_same_bits)
{
    glctx_pin_determinism(2);
    static float a[S * S * 4], b[S * S * 4], d[S * S * 4];
    char ra[128], rb[128], rd[128];
    probe("osmesa", -1, "offscreen", a, ra);
    probe("egl", -1, "surfaceless", b, rb);
    probe("egl", 0, "device 0", d, rd);
    ck_assert_msg(strstr(ra, "llvmpipe") && strstr(ra, "128 bits"), "pinned llvmpipe: %s", ra);
    ck_assert_str_eq(rb, ra);
    int varied = 0;
    for (int i = 1; i < S * S * 4; i++)
        varied |= a[i] != a[0];
    ck_assert(varied); /* the probe really computed something */
    ck_assert(memcmp(a, b, sizeof a) == 0);
    if (strstr(rd, "llvmpipe")) { /* a machine without a GPU: EGL device 0 is the same llvmpipe */
        ck_assert_str_eq(rd, ra);
        ck_assert(memcmp(a, d, sizeof a) == 0);
    } else {
        /* A GPU (the machines the EGL backend is for): another renderer, so not llvmpipe's bits,
         * but the probe must run there and compute the same functions (transcendentals to a
         * GPU's precision: nearly every value within 1 %). */
        int close = 0;
        for (int i = 0; i < S * S * 4; i++) {
            ck_assert_msg(isfinite(d[i]) == isfinite(a[i]), "%s: value %d: %g, llvmpipe %g", rd, i, d[i], a[i]);
            close += fabsf(d[i] - a[i]) <= 1e-2f * fmaxf(1.0f, fabsf(a[i]));
        }
        ck_assert_msg(close >= S * S * 4 * 95 / 100, "%s: %d of %d values within 1 %% of llvmpipe's", rd, close,
                      S * S * 4);
    }
}
END_TEST

static Suite *glctx_suite(void)
{
    Suite *s = suite_create("glctx");
    TCase *t = tcase_create("backends");
    tcase_set_timeout(t, 60);
    tcase_add_test(t, backend_names);
    tcase_add_test(t, unknown_backend_is_one_line_invalid);
    tcase_add_test(t, egl_device_out_of_range_is_invalid);
    tcase_add_test(t, osmesa_and_egl_give_the_same_bits);
    suite_add_tcase(s, t);
    return s;
}

int main(void)
{
    SRunner *sr = srunner_create(glctx_suite());
    srunner_run_all(sr, CK_NORMAL);
    int failed = srunner_ntests_failed(sr);
    srunner_free(sr);
    return failed ? EXIT_FAILURE : EXIT_SUCCESS;
}
