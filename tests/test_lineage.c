/* test_lineage.c — pixel lineage (replay/compare/lineage.h) on hand-made frames: a photon map of two
 * covering photons of known power (and two that must not count) gives the contributions of ISPM
 * 003 §5 Eq. 1–3 computed by hand, adding up to the splat buffer; a directional light's shadow
 * test lands on the texel the matrices say and turns from lit to shadowed with the stored depth;
 * a subsampled level is read at the scaled coordinate; motion vectors lead to the pixel of the
 * previous frame and back. */
#include "lineage.h"

#include <check.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

static const char *const XYZ[] = {"X", "Y", "Z"};
static const char *const XY[] = {"X", "Y"};
static const char *const RGB[] = {"R", "G", "B"};
static const char *const Z1[] = {"Z"};
static const char *const Y1[] = {"Y"};
/* As an EXR file gives them: sorted by name. */
static const char *const MAT[] = {"id", "ior", "metallic", "roughness", "transmission"};
static const char *const PH[] = {"position.X", "position.Y", "position.Z", "direction.X", "direction.Y",
                                 "direction.Z", "power.R",    "power.G",    "power.B",     "normal.X",
                                 "normal.Y",   "normal.Z",   "density",    "bounce"};
static const char *const ORG[] = {"light", "face", "texel.X", "texel.Y", "radius"};

/* A 2x2 frame whose every pixel sees the floor point (0, 0, 0), normal +Y, albedo 0.5, rough
 * dielectric; the photons and the splat buffer as given. */
typedef struct fixture {
    float pos[12], nrm[12], alb[12], mat[20], dep[4], mot[8], splat[12], count[4], level[3];
    float ph[4 * 14], org[4 * 5], shadow[16];
    eng_buffer bufs[16];
    lin_manifest m;
    lin_frame_meta meta;
    lin_frame fr;
} fixture;

static void photon(float *p, float px, float py, float pz, float dy, float r, float g, float b)
{
    float v[14] = {px, py, pz, 0.0f, dy, 0.0f, r, g, b, 0.0f, 1.0f, 0.0f, 0.5f, 2.0f};
    memcpy(p, v, sizeof v);
}

static void setup(fixture *f)
{
    memset(f, 0, sizeof *f);
    for (int i = 0; i < 4; i++) {
        f->nrm[3 * i + 1] = 1.0f;
        for (int c = 0; c < 3; c++)
            f->alb[3 * i + c] = 0.5f;
        float m[5] = {0.0f, 1.5f, 0.0f, 1.0f, 0.0f}; /* id ior metallic roughness transmission */
        memcpy(f->mat + 5 * i, m, sizeof m);
        f->dep[i] = 3.0f;
    }
    /* 1: at the point, power (1, 2, 3): κ = 2/(π r²) = 8/π for r = 0.5. 2: 0.25 m away in the
     * plane, power (2, 2, 2): t = 0.5, κ = 8/π · 0.75 = 6/π. 3: 0.2 m above the plane: t = 0.2/0.5
     * · (1 + (0.5 − 0.125)/0.125) = 1.6, outside. 4: at the point but arriving from below. */
    photon(f->ph, 0.0f, 0.0f, 0.0f, 1.0f, 1.0f, 2.0f, 3.0f);
    photon(f->ph + 14, 0.25f, 0.0f, 0.0f, 1.0f, 2.0f, 2.0f, 2.0f);
    photon(f->ph + 28, 0.0f, 0.2f, 0.0f, 1.0f, 5.0f, 5.0f, 5.0f);
    photon(f->ph + 42, 0.0f, 0.0f, 0.0f, -1.0f, 5.0f, 5.0f, 5.0f);
    for (int i = 0; i < 4; i++) {
        float o[5] = {0.0f, 0.0f, (float)(3 + i), 7.0f, 0.5f};
        memcpy(f->org + 5 * i, o, sizeof o);
    }
    const double pi = 3.14159265358979323846;
    for (int i = 0; i < 4; i++) {
        for (int c = 0; c < 3; c++)
            f->splat[3 * i + c] = (float)((double)(c + 1) * 4.0 / (pi * pi) + 6.0 / (pi * pi));
        f->count[i] = 2.0f;
    }
    f->level[0] = 7.0f;
    for (int i = 0; i < 16; i++)
        f->shadow[i] = 2.5f;
    int n = 0;
    f->bufs[n++] = (eng_buffer){"gbuffer.position", 2, 2, 3, XYZ, f->pos};
    f->bufs[n++] = (eng_buffer){"gbuffer.normal", 2, 2, 3, XYZ, f->nrm};
    f->bufs[n++] = (eng_buffer){"gbuffer.albedo", 2, 2, 3, RGB, f->alb};
    f->bufs[n++] = (eng_buffer){"gbuffer.material", 2, 2, 5, MAT, f->mat};
    f->bufs[n++] = (eng_buffer){"gbuffer.depth", 2, 2, 1, Z1, f->dep};
    f->bufs[n++] = (eng_buffer){"gbuffer.motion", 2, 2, 2, XY, f->mot};
    f->bufs[n++] = (eng_buffer){"photons.map", 4, 1, 14, PH, f->ph};
    f->bufs[n++] = (eng_buffer){"photons.origin", 4, 1, 5, ORG, f->org};
    f->bufs[n++] = (eng_buffer){"splat.indirect", 2, 2, 3, RGB, f->splat};
    f->bufs[n++] = (eng_buffer){"splat.count", 2, 2, 1, Y1, f->count};
    f->bufs[n++] = (eng_buffer){"upsample.level1", 1, 1, 3, RGB, f->level};
    f->bufs[n++] = (eng_buffer){"shadow.light0", 4, 4, 1, Z1, f->shadow};
    f->m.width = f->m.height = 2;
    f->m.frame_count = 1;
    strcpy(f->m.indirect, "ispm");
    f->m.compression = 0.25f;
    f->m.shadow_bias = 0.002f;
    f->m.pcf_radius = 0;
    f->meta.eye[1] = 3.0f;
    f->meta.eye[2] = 0.001f;
    /* A directional light straight down; its ortho view maps x, z in [−2, 2] to clip x, y. */
    f->meta.light_count = 1;
    eng_light_record *L = &f->meta.lights[0];
    L->type = 2;
    L->faces = 1;
    L->position[1] = 2.0f;
    L->direction[1] = -1.0f;
    L->far_value = 4.0f;
    L->texel = 1.0f / 4.0f / 4.0f; /* kept small so that the normal offset is small */
    L->view_proj[0][0] = 0.5f;     /* row 0, column 0 */
    L->view_proj[0][9] = 0.5f;     /* row 1, column 2 */
    L->view_proj[0][15] = 1.0f;
    f->fr = (lin_frame){f->bufs, n, &f->m, &f->meta};
}

START_TEST(two_photons_of_known_power)
{
    fixture *f = malloc(sizeof *f);
    setup(f);
    lin_result r;
    eng_error err;
    ck_assert_int_eq(lin_pixel(&f->fr, 1, 0, &r, &err), ENG_OK);
    ck_assert(r.covered);
    ck_assert(r.has_photons);
    ck_assert_int_eq(r.map_photons, 4);
    ck_assert_int_eq(r.photon_count, 2);
    const double pi = 3.14159265358979323846;
    /* f Φ κ with f = 0.5/π: photon 1 → 4 Φ/π², photon 2 → 0.5/π · 2 · 6/π = 6/π². */
    for (int c = 0; c < 3; c++) {
        double want1 = (double)(c + 1) * 4.0 / (pi * pi), want2 = 6.0 / (pi * pi);
        ck_assert_double_eq_tol(r.photons[0].contribution[c], want1, 1e-6 * want1);
        ck_assert_double_eq_tol(r.photons[1].contribution[c], want2, 1e-6 * want2);
        ck_assert_double_eq_tol(r.sum[c], (double)r.splat[c], 1e-6 * (double)r.splat[c]);
    }
    ck_assert_int_eq(r.photons[0].index, 0);
    ck_assert_int_eq(r.photons[1].index, 1);
    ck_assert_int_eq(r.photons[1].texel[0], 4);
    ck_assert_int_eq(r.photons[1].texel[1], 7);
    ck_assert(r.has_splat);
    ck_assert_float_eq(r.splat_count, 2.0f);
    ck_assert_str_eq(r.splat_name, "splat.indirect");
    lin_result_free(&r);
    /* The quads' kernel is another one: not listed, and said why. */
    strcpy(f->m.indirect, "quads");
    ck_assert_int_eq(lin_pixel(&f->fr, 1, 0, &r, &err), ENG_OK);
    ck_assert(!r.has_photons);
    ck_assert_ptr_nonnull(r.why);
    lin_result_free(&r);
    /* Nor do the final gather's pixels come from kernels at the pixel. */
    strcpy(f->m.indirect, "final-gather");
    ck_assert_int_eq(lin_pixel(&f->fr, 1, 0, &r, &err), ENG_OK);
    ck_assert(!r.has_photons);
    ck_assert_ptr_nonnull(r.why);
    ck_assert_ptr_nonnull(strstr(r.why, "final gather"));
    lin_result_free(&r);
    /* Without photons.origin the photons cannot be evaluated. */
    strcpy(f->m.indirect, "kd-gather");
    f->fr.count = 7;
    ck_assert_int_eq(lin_pixel(&f->fr, 1, 0, &r, &err), ENG_OK);
    ck_assert(!r.has_photons);
    lin_result_free(&r);
    ck_assert_int_eq(lin_pixel(&f->fr, 2, 0, &r, &err), ENG_ERR_INVALID);
    free(f);
}
END_TEST

START_TEST(shadow_texel_and_verdict)
{
    fixture *f = malloc(sizeof *f);
    setup(f);
    lin_result r;
    eng_error err;
    ck_assert_int_eq(lin_pixel(&f->fr, 0, 1, &r, &err), ENG_OK);
    ck_assert_int_eq(r.shadow_count, 1);
    lin_shadow *s = &r.shadows[0];
    /* (0, 0, 0) maps to uv (0.5, 0.5): texel 2 of 4 from the bottom, row 1 from the top. */
    ck_assert_float_eq_tol(s->uv[0], 0.5f, 1e-6f);
    ck_assert_float_eq_tol(s->uv[1], 0.5f, 1e-6f);
    ck_assert_int_eq(s->texel[0], 2);
    ck_assert_int_eq(s->texel[1], 1);
    ck_assert_float_eq(s->distance, 2.0f);
    ck_assert_float_eq(s->stored, 2.5f);
    ck_assert(s->lit);
    ck_assert_float_eq(s->visibility, 1.0f);
    lin_result_free(&r);
    f->shadow[1 * 4 + 2] = 1.0f; /* an occluder 1 m below the light at that texel */
    ck_assert_int_eq(lin_pixel(&f->fr, 0, 1, &r, &err), ENG_OK);
    ck_assert(!r.shadows[0].lit);
    ck_assert_float_eq(r.shadows[0].visibility, 0.0f);
    /* Every other buffer at its own coordinate: the 1x1 level at (0, 0), the shadow map's own
     * value listed at the texel. */
    int level = 0, map = 0;
    for (int i = 0; i < r.value_count; i++) {
        if (strcmp(r.values[i].name, "upsample.level1") == 0) {
            level = 1;
            ck_assert_int_eq(r.values[i].x, 0);
            ck_assert_float_eq(r.values[i].v[0], 7.0f);
        }
        if (strcmp(r.values[i].name, "shadow.light0") == 0) {
            map = 1;
            ck_assert_int_eq(r.values[i].x, 2);
            ck_assert_int_eq(r.values[i].y, 1);
            ck_assert_float_eq(r.values[i].v[0], 1.0f);
        }
    }
    ck_assert(level && map);
    lin_result_free(&r);
    free(f);
}
END_TEST

START_TEST(motion_vectors_lead_back_and_forward)
{
    fixture *f = malloc(sizeof *f);
    setup(f);
    /* Pixel (1, 1) was at (0, 0) in the previous frame: motion (−1, −1); the others moved far. */
    for (int i = 0; i < 8; i++)
        f->mot[i] = 5.0f;
    f->mot[(1 * 2 + 1) * 2] = -1.0f;
    f->mot[(1 * 2 + 1) * 2 + 1] = -1.0f;
    int x, y;
    ck_assert(lin_follow_back(&f->fr, 1, 1, &x, &y));
    ck_assert_int_eq(x, 0);
    ck_assert_int_eq(y, 0);
    ck_assert(lin_follow_forward(&f->fr, 0, 0, 1, &x, &y));
    ck_assert_int_eq(x, 1);
    ck_assert_int_eq(y, 1);
    /* Leaving the image: no previous pixel. */
    f->mot[0] = -3.0f;
    ck_assert(!lin_follow_back(&f->fr, 0, 0, &x, &y));
    free(f);
}
END_TEST

START_TEST(subsampled_irradiance_level)
{
    /* The method ran at a 1x1 level in irradiance mode (Φ κ, no BSDF): the photons are
     * evaluated at the level's own surface point, here the same floor point. */
    fixture *f = malloc(sizeof *f);
    setup(f);
    static float lpos[3] = {0.0f, 0.0f, 0.0f}, lnrm[3] = {0.0f, 1.0f, 0.0f}, ldep[1] = {3.0f}, irr[3], cnt[1] = {2.0f};
    const double pi = 3.14159265358979323846;
    for (int c = 0; c < 3; c++)
        irr[c] = (float)(((double)(c + 1) * 8.0 + 12.0) / pi); /* (1, 2, 3)·8/π + 2·6/π */
    f->bufs[8] = (eng_buffer){"splat.irradiance", 1, 1, 3, RGB, irr};
    f->bufs[9] = (eng_buffer){"splat.count", 1, 1, 1, Y1, cnt};
    int n = f->fr.count;
    f->bufs[n++] = (eng_buffer){"gbuffer.level1.position", 1, 1, 3, XYZ, lpos};
    f->bufs[n++] = (eng_buffer){"gbuffer.level1.normal", 1, 1, 3, XYZ, lnrm};
    f->bufs[n++] = (eng_buffer){"gbuffer.level1.depth", 1, 1, 1, Z1, ldep};
    f->fr.count = n;
    lin_result r;
    eng_error err;
    ck_assert_int_eq(lin_pixel(&f->fr, 1, 1, &r, &err), ENG_OK);
    ck_assert(r.irradiance && r.has_splat && r.splat_covered);
    ck_assert_int_eq(r.splat_level, 1);
    ck_assert_int_eq(r.photon_count, 2);
    for (int c = 0; c < 3; c++)
        ck_assert_double_eq_tol(r.sum[c], (double)irr[c], 1e-6 * (double)irr[c]);
    lin_result_free(&r);
    free(f);
}
END_TEST

int main(void)
{
    Suite *s = suite_create("lineage");
    TCase *tc = tcase_create("core");
    tcase_add_test(tc, two_photons_of_known_power);
    tcase_add_test(tc, shadow_texel_and_verdict);
    tcase_add_test(tc, motion_vectors_lead_back_and_forward);
    tcase_add_test(tc, subsampled_irradiance_level);
    suite_add_tcase(s, tc);
    SRunner *sr = srunner_create(s);
    srunner_run_all(sr, CK_NORMAL);
    int failed = srunner_ntests_failed(sr);
    srunner_free(sr);
    return failed ? EXIT_FAILURE : EXIT_SUCCESS;
}
