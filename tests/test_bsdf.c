/* test_bsdf.c — one BSDF sampling on both processors: engine/trace/bsdf.c (the CPU trace) and its
 * GLSL twin engine/gl/shaders/bsdf_sample.glsl (the bounce map) are fed the same random numbers
 * for every material class (diffuse, rough and smooth metal, glass, a glTF mixture of all
 * three) through a probe fragment shader (shaders/bsdf_probe.frag.glsl) on the engine's OSMesa
 * context, and must choose the same lobe and return the same direction, weight, path-density
 * factor and medium; bsdf_stratify (stratified sampling across frames, 002_… §4.2) likewise.
 * Also the stratification itself: rmap_frame's offsets put every dimension in each of the K
 * strata once per cycle and repeat every K frames. And stratified first bounces within a frame
 * (bsdf_strata): C and GLSL bit-identical, every block covering each stratum once. */
#include "bsdf.h"
#include "trace.h"

#include <check.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define W 256
#define ROWS_PER_CLASS 16
#define CLASSES 5
#define H (ROWS_PER_CLASS * CLASSES)
#define N ((size_t)W * H)

static uint64_t test_rng(uint64_t *state)
{
    uint64_t z = (*state += 0x9E3779B97F4A7C15ull);
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
    return z ^ (z >> 31);
}

static float test_uniform(uint64_t *state)
{
    return (float)(test_rng(state) >> 40) * (1.0f / 16777216.0f);
}

static void unit_vector(uint64_t *st, float out[3])
{
    float z = 1.0f - 2.0f * test_uniform(st), phi = 6.2831853f * test_uniform(st);
    float r = sqrtf(fmaxf(0.0f, 1.0f - z * z));
    out[0] = r * cosf(phi);
    out[1] = r * sinf(phi);
    out[2] = z;
}

static scn_material class_material(int c)
{
    scn_material m;
    memset(&m, 0, sizeof m);
    m.ior = 1.5f;
    m.roughness = 1.0f;
    m.base_color[3] = 1.0f;
    const float colours[CLASSES][3] = {
        {0.8f, 0.5f, 0.3f}, {0.9f, 0.6f, 0.2f}, {0.95f, 0.9f, 0.8f}, {0.9f, 0.95f, 1.0f}, {0.7f, 0.7f, 0.5f}};
    memcpy(m.base_color, colours[c], sizeof colours[c]);
    switch (c) {
    case 0: /* diffuse */
        break;
    case 1: /* rough metal */
        m.metallic = 1.0f;
        m.roughness = 0.4f;
        break;
    case 2: /* smooth metal: below BSDF_MIRROR_ROUGHNESS, a mirror */
        m.metallic = 1.0f;
        m.roughness = 0.005f;
        break;
    case 3: /* glass */
        m.transmission = 1.0f;
        m.roughness = 0.0f;
        break;
    default: /* the glTF mixture: metal, glass and diffuse lobes */
        m.metallic = 0.3f;
        m.transmission = 0.4f;
        m.roughness = 0.3f;
        break;
    }
    return m;
}

static const char *const class_name[CLASSES] = {"diffuse", "rough metal", "smooth metal", "glass", "mixed"};

static GLuint texture(const float *rgba)
{
    GLuint t;
    glGenTextures(1, &t);
    glBindTexture(GL_TEXTURE_2D, t);
    glTexImage2D(GL_TEXTURE_2D, 0, GL_RGBA32F, W, H, 0, GL_RGBA, GL_FLOAT, rgba);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, GL_NEAREST);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, GL_NEAREST);
    return t;
}

static float *download(GLuint tex)
{
    float *rgba = malloc(N * 4 * sizeof(float));
    glBindTexture(GL_TEXTURE_2D, tex);
    glGetTexImage(GL_TEXTURE_2D, 0, GL_RGBA, GL_FLOAT, rgba);
    return rgba;
}

static float rel_err(float a, float b)
{
    return fabsf(a - b) / fmaxf(1.0f, fmaxf(fabsf(a), fabsf(b)));
}

START_TEST(glsl_matches_c)
{
    eng_error err;
    glctx_pin_determinism(2);
    eng_glctx *ctx = NULL;
    ck_assert_msg(glctx_create(&ctx, &err) == ENG_OK, "%s", err.msg);
    eng_random_maps rm;
    ck_assert_int_eq(rmap_create(7, 1u << 16, &rm, &err), ENG_OK);

    enum { T_BASE, T_MAT, T_N, T_WI, T_U, T_COS, T_OFF, T_STRATA, T_COUNT };
    float *in[T_COUNT];
    for (int t = 0; t < T_COUNT; t++)
        in[t] = calloc(N * 4, sizeof(float));
    uint64_t st = 99;
    for (size_t i = 0; i < N; i++) {
        int c = (int)(i / W / ROWS_PER_CLASS);
        scn_material m = class_material(c);
        memcpy(in[T_BASE] + 4 * i, m.base_color, 3 * sizeof(float));
        in[T_BASE][4 * i + 3] = (test_rng(&st) & 3) == 0 ? 1.33f : 1.0f; /* medium before */
        float *mat = in[T_MAT] + 4 * i;
        mat[0] = m.roughness;
        mat[1] = m.metallic;
        mat[2] = m.transmission;
        mat[3] = m.ior;
        unit_vector(&st, in[T_N] + 4 * i);
        unit_vector(&st, in[T_WI] + 4 * i); /* either side: glass enters and leaves */
        for (int d = 0; d < 4; d++) {
            in[T_U][4 * i + d] = test_uniform(&st);
            in[T_OFF][4 * i + d] = (float)(test_rng(&st) % 16) / 16.0f;
        }
        /* bsdf_strata: a block size 2..16, a place in the block, a 32-bit pattern (two halves). */
        uint32_t log2n = 1u + (uint32_t)(test_rng(&st) % BSDF_STRATA_MAX_LOG2), pattern = (uint32_t)test_rng(&st);
        in[T_STRATA][4 * i] = (float)(test_rng(&st) % (1u << (2 * log2n)));
        in[T_STRATA][4 * i + 1] = (float)log2n;
        in[T_STRATA][4 * i + 2] = (float)(pattern & 0xffffu);
        in[T_STRATA][4 * i + 3] = (float)(pattern >> 16);
        memcpy(in[T_COS] + 4 * i, rm.cosine + 4 * (i & (rm.size - 1)), 4 * sizeof(float));
    }

    glu_pass p;
    ck_assert_msg(glu_pass_create(&p, "bsdf_probe.frag.glsl", 6, W, H, &err) == ENG_OK, "%s", err.msg);
    static const char *const names[T_COUNT] = {"u_base", "u_mat", "u_n", "u_wi", "u_u", "u_cosdir", "u_offset",
                                                 "u_strata"};
    GLuint tex[T_COUNT];
    glUseProgram(p.program);
    for (int t = 0; t < T_COUNT; t++) {
        glActiveTexture(GL_TEXTURE0 + (GLenum)t);
        tex[t] = texture(in[t]);
        glUniform1i(glGetUniformLocation(p.program, names[t]), t);
    }
    glu_pass_draw(&p);
    glFinish();
    float *o_wo = download(p.target.color[0]), *o_w = download(p.target.color[1]);
    float *o_eta = download(p.target.color[2]), *o_su = download(p.target.color[3]);
    float *o_scd = download(p.target.color[4]), *o_strata = download(p.target.color[5]);

    /* bsdf_strata is integer hashing and exact float arithmetic: bit-identical. */
    size_t strata_diff = 0;
    for (size_t i = 0; i < N; i++) {
        const float *stv = in[T_STRATA] + 4 * i;
        float su[4];
        bsdf_strata(in[T_U] + 4 * i, (uint32_t)stv[0], (uint32_t)stv[1], (uint32_t)stv[2] | (uint32_t)stv[3] << 16, su);
        strata_diff += memcmp(su, o_strata + 4 * i, sizeof su) != 0;
    }
    printf("bsdf: bsdf_strata: %zu of %zu samples differ between C and GLSL\n", strata_diff, N);
    ck_assert_msg(strata_diff == 0, "bsdf_strata: %zu samples differ between C and GLSL", strata_diff);

    /* Lobe choice is exact arithmetic on the inputs except where Russian roulette or the
     * Fresnel choice compares u with a computed value (llvmpipe's sin/cos/atan are not
     * libm's): a handful of such coin flips may differ, never more than 1 in 2000. */
    for (int c = 0; c < CLASSES; c++) {
        size_t lobe_diff = 0, alive = 0, lobes[6] = {0};
        float e_wo = 0.0f, e_w = 0.0f, e_rho = 0.0f, e_eta = 0.0f, e_cd = 0.0f;
        int su_exact = 1;
        for (size_t i = (size_t)c * W * ROWS_PER_CLASS; i < (size_t)(c + 1) * W * ROWS_PER_CLASS; i++) {
            scn_material m = class_material(c);
            float eta = in[T_BASE][4 * i + 3];
            bsdf_sample rnd = {in[T_U] + 4 * i, in[T_COS] + 4 * i};
            float wo[3], w[3], rho;
            bsdf_lobe lobe = bsdf_scatter(&m, in[T_N] + 4 * i, in[T_WI] + 4 * i, &eta, &rnd, wo, w, &rho);
            lobes[lobe]++;
            if ((int)o_wo[4 * i + 3] != (int)lobe) {
                lobe_diff++;
                continue;
            }
            alive += lobe != BSDF_ABSORBED;
            for (int k = 0; k < 3; k++) {
                e_wo = fmaxf(e_wo, fabsf(wo[k] - o_wo[4 * i + k]));
                e_w = fmaxf(e_w, rel_err(w[k], o_w[4 * i + k]));
            }
            e_rho = fmaxf(e_rho, fabsf(rho - o_w[4 * i + 3]) / fmaxf(fabsf(rho), 1e-6f));
            e_eta = fmaxf(e_eta, fabsf(eta - o_eta[4 * i]));
            float su[4], scd[4];
            bsdf_stratify(in[T_U] + 4 * i, in[T_OFF] + 4 * i, su, scd);
            su_exact &= memcmp(su, o_su + 4 * i, sizeof su) == 0;
            for (int k = 0; k < 4; k++)
                e_cd = fmaxf(e_cd, fabsf(scd[k] - o_scd[4 * i + k]));
        }
        printf("bsdf: %-12s lobes diffuse %zu glossy %zu mirror %zu reflect %zu refract %zu absorbed %zu; "
               "%zu lobe choices differ; max |Δwo| %.2g, rel Δweight %.2g, rel Δρ %.2g, |Δη| %.2g, "
               "stratify |Δcosdir| %.2g\n",
               class_name[c], lobes[BSDF_DIFFUSE], lobes[BSDF_GLOSSY], lobes[BSDF_MIRROR], lobes[BSDF_REFLECT],
               lobes[BSDF_REFRACT], lobes[BSDF_ABSORBED], lobe_diff, (double)e_wo, (double)e_w, (double)e_rho,
               (double)e_eta, (double)e_cd);
        ck_assert_msg(lobe_diff * 2000 <= (size_t)W * ROWS_PER_CLASS, "%s: %zu lobe choices differ", class_name[c],
                      lobe_diff);
        ck_assert_msg(alive > (size_t)W * ROWS_PER_CLASS / 4, "%s: too few surviving samples", class_name[c]);
        ck_assert_msg(e_wo < 2e-4f, "%s: direction differs by %g", class_name[c], (double)e_wo);
        ck_assert_msg(e_w < 2e-4f, "%s: weight differs by %g", class_name[c], (double)e_w);
        ck_assert_msg(e_rho < 1e-3f, "%s: path density differs by %g", class_name[c], (double)e_rho);
        ck_assert_msg(e_eta == 0.0f, "%s: medium differs by %g", class_name[c], (double)e_eta);
        ck_assert_msg(su_exact, "%s: the Cranley-Patterson rotation is not bit-identical", class_name[c]);
        ck_assert_msg(e_cd < 2e-5f, "%s: stratified cosine direction differs by %g", class_name[c], (double)e_cd);
    }
    /* Every class reached the lobes it has. */
    free(o_wo);
    free(o_w);
    free(o_eta);
    free(o_su);
    free(o_scd);
    free(o_strata);
    glDeleteTextures(T_COUNT, tex);
    glu_pass_destroy(&p);
    for (int t = 0; t < T_COUNT; t++)
        free(in[t]);
    rmap_destroy(&rm);
    glctx_destroy(ctx);
}
END_TEST

/* Over one cycle of K frames each dimension's offset visits every stratum j/K once, so a
 * rotated number visits each stratum [j/K, (j+1)/K) once; frame f and f + K read the same;
 * the direction pair (d = 2, 3) is a rank-1 lattice, not the diagonal. */
START_TEST(stratified_offsets)
{
    eng_settings s;
    memset(&s, 0, sizeof s);
    s.random = ENG_RANDOM_STRATIFIED;
    const int cycles[] = {1, 2, 4, 7, 16, 64};
    for (size_t ci = 0; ci < sizeof cycles / sizeof cycles[0]; ci++) {
        int K = cycles[ci];
        s.stratified_cycle = K;
        const float u[4] = {0.123f, 0.999f, 0.5f, 0.01f};
        int seen[4][64];
        memset(seen, 0, sizeof seen);
        int diagonal = 1;
        for (int f = 0; f < K; f++) {
            eng_rmap_frame a, b;
            rmap_frame(&s, f, &a);
            rmap_frame(&s, f + 3 * K, &b);
            ck_assert_int_eq(a.stratified, 1);
            ck_assert_uint_eq(a.salt, 0);
            ck_assert_int_eq(memcmp(&a, &b, sizeof a), 0);
            float su[4], cd[4];
            bsdf_stratify(u, a.offset, su, cd);
            for (int d = 0; d < 4; d++) {
                ck_assert(su[d] >= 0.0f && su[d] < 1.0f);
                int j = (int)(su[d] * (float)K);
                ck_assert(j >= 0 && j < K);
                seen[d][j]++;
            }
            diagonal &= a.offset[2] == a.offset[3];
            ck_assert(fabsf(cd[0] * cd[0] + cd[1] * cd[1] + cd[2] * cd[2] - 1.0f) < 1e-5f);
        }
        for (int d = 0; d < 4; d++)
            for (int j = 0; j < K; j++)
                ck_assert_msg(seen[d][j] == 1, "K=%d dimension %d stratum %d visited %d times", K, d, j, seen[d][j]);
        if (K >= 4)
            ck_assert_msg(!diagonal, "K=%d: the direction pair moves along the diagonal", K);
    }
    /* Not stratified: no rotation; per-frame salts by frame. */
    s.random = ENG_RANDOM_MAPS;
    eng_rmap_frame r;
    rmap_frame(&s, 5, &r);
    ck_assert(r.stratified == 0 && r.salt == 0 && r.offset[0] == 0.0f);
    s.random = ENG_RANDOM_PER_FRAME;
    rmap_frame(&s, 5, &r);
    ck_assert(r.stratified == 0 && r.salt == 6);
}
END_TEST

/* Stratified first bounces (bsdf_strata, Kensler 2013 correlated multi-jitter): bsdf_permute is
 * a permutation; over one block's N² samples the direction pair has one sample in each cell of
 * the N×N grid and in each of the N² columns and rows, the lobe and roulette numbers one in each
 * of N² intervals; the patterns of two blocks differ; the jitter is the place within its stratum; a
 * jitter next to 1 gives a number below 1. */
START_TEST(strata_cover_each_stratum_once)
{
    for (uint32_t l = 1; l <= 300; l += (l < 20 ? 1 : 37))
        for (uint32_t p = 0; p < 5; p++) {
            uint32_t pattern = p * 0x9e3779b9u + 12345u;
            unsigned char seen[300] = {0};
            for (uint32_t i = 0; i < l; i++) {
                uint32_t j = bsdf_permute(i, l, pattern);
                ck_assert_uint_lt(j, l);
                ck_assert_msg(!seen[j], "bsdf_permute(·, %u, %u) is not a permutation", l, pattern);
                seen[j] = 1;
            }
        }
    uint64_t st = 5;
    for (uint32_t k = 1; k <= BSDF_STRATA_MAX_LOG2; k++) {
        uint32_t n = 1u << k, m = n * n;
        int differs = 0;
        static float first[4096][4];
        for (int block = 0; block < 8; block++) {
            uint32_t pattern = (uint32_t)test_rng(&st);
            static int cell[4096], col[4096], row[4096], lobe[4096], rr[4096];
            memset(cell, 0, sizeof cell);
            memset(col, 0, sizeof col);
            memset(row, 0, sizeof row);
            memset(lobe, 0, sizeof lobe);
            memset(rr, 0, sizeof rr);
            for (uint32_t i = 0; i < m; i++) {
                float u[4], out[4];
                for (int d = 0; d < 4; d++)
                    u[d] = test_uniform(&st) * 0.999f; /* clear of the round-up next to 1, below */
                bsdf_strata(u, i, k, pattern, out);
                for (int d = 0; d < 4; d++) {
                    ck_assert(out[d] >= 0.0f && out[d] < 1.0f);
                    /* the jitter is the position within the stratum, exactly */
                    float f = out[d] * (float)m;
                    /* up to the float spacing of the sum stratum + u (< m) */
                    ck_assert_msg(fabsf(f - floorf(f) - u[d]) <= (float)m * 0x1p-23f,
                                  "jitter %g became %g", (double)u[d], (double)(f - floorf(f)));
                }
                uint32_t fx = (uint32_t)(out[BSDF_U_DIR0] * (float)m), fy = (uint32_t)(out[BSDF_U_DIR1] * (float)m);
                cell[(fy / n) * n + fx / n]++;
                col[fx]++;
                row[fy]++;
                lobe[(uint32_t)(out[BSDF_U_LOBE] * (float)m)]++;
                rr[(uint32_t)(out[BSDF_U_ROULETTE] * (float)m)]++;
                if (block == 0)
                    memcpy(first[i], out, sizeof out);
                else
                    differs |= fabsf(first[i][BSDF_U_DIR0] - out[BSDF_U_DIR0]) * (float)n >= 1.0f;
            }
            for (uint32_t j = 0; j < m; j++) {
                ck_assert_msg(cell[j] == 1, "N=%u: grid cell %u holds %d samples", n, j, cell[j]);
                ck_assert_msg(col[j] == 1 && row[j] == 1, "N=%u: column/row %u: %d/%d samples", n, j, col[j], row[j]);
                ck_assert_msg(lobe[j] == 1 && rr[j] == 1, "N=%u: 1D stratum %u: %d/%d samples", n, j, lobe[j], rr[j]);
            }
        }
        ck_assert_msg(differs, "N=%u: every block puts each texel in the same coarse stratum", n);
        const float top[4] = {0x1.fffffep-1f, 0x1.fffffep-1f, 0x1.fffffep-1f, 0x1.fffffep-1f};
        for (uint32_t i = 0; i < m; i++) {
            float out[4];
            bsdf_strata(top, i, k, 77u, out);
            for (int d = 0; d < 4; d++)
                ck_assert(out[d] < 1.0f);
        }
    }
}
END_TEST

#if defined(__SSE2__)
/* bsdf_diffuse4 (the photon trace's diffuse lobe, four hits at once) against
 * bsdf_scatter_params, lane by lane, bit for bit: random normals (either side of wi),
 * albedos up to 1 with zero and out-of-range channels, cosine directions from the tables'
 * range, and roulette numbers that keep and end paths; fewer than four lanes repeat lane 0. */
START_TEST(diffuse4_matches_scalar)
{
    uint32_t state = 0x9E3779B9u;
#define RND() ((state = state * 1664525u + 1013904223u) >> 8) * (1.0f / 16777216.0f)
    int kept = 0, ended = 0, checked = 0;
    for (int round = 0; round < 20000; round++) {
        const int lanes = 1 + round % 4;
        float n[4][3], wi[4][3], cd[4][4], u[4][4], out_wo[4][3], out_w[4][3], out_d[4];
        bsdf_params m[4];
        const float *pn[4], *pwi[4], *pcd[4], *palb[4];
        float ur[4], *pwo[4], *pw[4], *pd[4];
        int alive[4];
        for (int k = 0; k < 4; k++) {
            const int src = k < lanes ? k : 0;
            if (k < lanes) {
                float len;
                do {
                    for (int i = 0; i < 3; i++) {
                        n[k][i] = 2.0f * RND() - 1.0f;
                        wi[k][i] = 2.0f * RND() - 1.0f;
                    }
                    len = sqrtf(n[k][0] * n[k][0] + n[k][1] * n[k][1] + n[k][2] * n[k][2]);
                } while (len < 0.1f);
                for (int i = 0; i < 3; i++)
                    n[k][i] /= len;
                float phi = 6.2831853f * RND(), ct = sqrtf(RND()), st = sqrtf(1.0f - ct * ct);
                cd[k][0] = st * cosf(phi);
                cd[k][1] = st * sinf(phi);
                cd[k][2] = ct;
                cd[k][3] = ct / 3.14159265f;
                for (int d = 0; d < 4; d++)
                    u[k][d] = RND();
                m[k] = (bsdf_params){{RND(), RND() * 1.2f, round % 7 == 0 ? 0.0f : RND()}, 0.0f, 1.0f, 0.0f, 1.5f};
            }
            pn[k] = n[src];
            pwi[k] = wi[src];
            pcd[k] = cd[src];
            palb[k] = m[src].base_color;
            ur[k] = u[src][BSDF_U_ROULETTE];
            pwo[k] = out_wo[src];
            pw[k] = out_w[src];
            pd[k] = &out_d[src];
        }
        bsdf_diffuse4(pn, pwi, pcd, palb, ur, pwo, pw, pd, alive);
        for (int k = 0; k < lanes; k++) {
            if (!bsdf_takes_diffuse(&m[k], n[k], wi[k], u[k]))
                continue; /* wi in the surface: not a diffuse hit */
            float eta = 1.0f, wo[3], w[3], d;
            const bsdf_sample rnd = {u[k], cd[k]};
            const bsdf_lobe lobe = bsdf_scatter_params(&m[k], n[k], wi[k], &eta, &rnd, wo, w, &d);
            ck_assert_int_eq(alive[k], lobe == BSDF_DIFFUSE);
            ck_assert_int_eq(memcmp(out_wo[k], wo, sizeof wo), 0);
            ck_assert_int_eq(memcmp(out_w[k], w, sizeof w), 0);
            ck_assert_int_eq(memcmp(&out_d[k], &d, sizeof d), 0);
            kept += alive[k];
            ended += !alive[k];
            checked++;
        }
    }
#undef RND
    printf("bsdf: diffuse4 = scalar on %d hits (%d kept, %d ended by roulette)\n", checked, kept, ended);
    ck_assert_int_gt(kept, 1000);
    ck_assert_int_gt(ended, 1000);
}
END_TEST
#endif

static Suite *bsdf_suite(void)
{
    Suite *s = suite_create("bsdf");
    TCase *tc = tcase_create("bsdf");
    tcase_set_timeout(tc, 600);
    tcase_add_test(tc, glsl_matches_c);
    tcase_add_test(tc, stratified_offsets);
    tcase_add_test(tc, strata_cover_each_stratum_once);
#if defined(__SSE2__)
    tcase_add_test(tc, diffuse4_matches_scalar);
#endif
    suite_add_tcase(s, tc);
    return s;
}

int main(void)
{
    SRunner *sr = srunner_create(bsdf_suite());
    srunner_run_all(sr, CK_NORMAL);
    int failed = srunner_ntests_failed(sr);
    srunner_free(sr);
    return failed ? EXIT_FAILURE : EXIT_SUCCESS;
}
