/* test_outputs.c — Check suite of the passes' output tables (passes.h "outputs"): every name a
 * table can produce is a part name of DESIGN.md's "Buffer (EXR part) names" table, and every
 * entry is well formed. The design's backticked part names become patterns (<i>, <f>, <k>: a
 * number; <part>: any name; [...]: optional; {a,b}: one of), and each table entry is expanded
 * for single- and six-face lights, several levels and every indirect method's prefix, as the
 * frame loop (engine.c) expands it. Names the engine announces that DESIGN.md does not list yet
 * are named in not_in_design, each of which must still be produced by some table. */
#include "indirect.h"
#include "shadow.h"

#include <check.h>
#include <regex.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define DESIGN_MD ISPM_SHARED_DIR "/DESIGN.md"
#define MAX_PATTERNS 128

typedef struct table_ref {
    const char *what;
    const pass_output *table;
} table_ref;

/* Every table the frame loop walks (the shadow methods' come from their registry). */
static const table_ref tables[] = {
    {"gbuffer", pass_gbuffer_outputs},
    {"gbuffer levels", pass_gbuffer_level_outputs},
    {"shadow", pass_shadow_outputs},
    {"lightmaps", pass_lightmaps_outputs},
    {"direct", pass_direct_outputs},
    {"upsample", pass_upsample_outputs},
    {"temporal", pass_temporal_outputs},
    {"atrous", pass_atrous_outputs},
    {"atrous result", pass_atrous_result_outputs},
    {"resolve", pass_resolve_outputs},
    {"composite", pass_composite_outputs},
    {"indirect radiance mode", ind_radiance_outputs},
    {"indirect irradiance mode", ind_irradiance_outputs},
};

/* Announced names DESIGN.md's table does not list (yet): full-name patterns. */
static const char *const not_in_design[] = {
    "^gbuffer\\.level[0-9]+\\.(position|normal|depth)$", /* the filters' subsampled G-buffers */
    "^temporal\\.alpha$",                                /* the temporal filter's α per pixel */
    "^splat\\.glossy$",                                  /* irradiance mode's glossy radiance */
    /* the gather methods' prefixes (the design names the estimate's parts splat.*) */
    "^(gather|final_gather)\\.(indirect|count|irradiance|glossy)$",
};
#define NOT_IN_DESIGN (int)(sizeof not_in_design / sizeof not_in_design[0])

typedef struct patterns {
    int count;
    char source[MAX_PATTERNS][160]; /* the design's spelling */
    regex_t re[MAX_PATTERNS];
} patterns;

/* Appends the regular expression of the design's part name `part` (n characters) to out. */
static void part_regex(const char *part, size_t n, char *out, size_t size)
{
    size_t o = 0;
#define PUT(str) (o += (size_t)snprintf(out + o, o < size ? size - o : 0, "%s", (str)))
    PUT("^");
    for (size_t i = 0; i < n; i++) {
        char c = part[i];
        if (c == '<') {
            size_t j = i;
            while (j < n && part[j] != '>')
                j++;
            PUT(j - i == 2 ? "[0-9]+" : "[A-Za-z0-9_.]+"); /* <i>, <f>, <k>; <part> */
            i = j;
        } else if (c == '[') {
            PUT("(");
        } else if (c == ']') {
            PUT(")?");
        } else if (c == '{') {
            PUT("(");
        } else if (c == '}') {
            PUT(")");
        } else if (c == ',') {
            PUT("|");
        } else if (c == '.') {
            PUT("\\.");
        } else {
            char s[2] = {c, '\0'};
            PUT(s);
        }
    }
    PUT("$");
#undef PUT
    ck_assert_uint_lt(o, size);
}

/* The backticked part names of the rows of DESIGN.md's "Buffer (EXR part) names" table, as
 * patterns; fails the test when the section or its table is missing. */
static void design_patterns(patterns *p)
{
    FILE *f = fopen(DESIGN_MD, "r");
    ck_assert_msg(f != NULL, "cannot open %s", DESIGN_MD);
    char line[2048];
    int in_section = 0, rows = 0;
    p->count = 0;
    while (fgets(line, sizeof line, f)) {
        if (strncmp(line, "## ", 3) == 0) {
            in_section = strstr(line, "Buffer (EXR part) names") != NULL;
            continue;
        }
        if (!in_section || line[0] != '|' || strstr(line, "| ---"))
            continue;
        rows++;
        for (char *a = strchr(line, '`'); a; a = strchr(a, '`')) {
            char *b = strchr(a + 1, '`');
            if (!b)
                break;
            size_t n = (size_t)(b - a - 1);
            /* Only part names: a dot and no spaces (the header row's words have neither). */
            if (memchr(a + 1, '.', n) && !memchr(a + 1, ' ', n)) {
                ck_assert_int_lt(p->count, MAX_PATTERNS);
                char re[512];
                snprintf(p->source[p->count], sizeof p->source[0], "%.*s", (int)n, a + 1);
                part_regex(a + 1, n, re, sizeof re);
                ck_assert_msg(regcomp(&p->re[p->count], re, REG_EXTENDED | REG_NOSUB) == 0, "bad pattern %s", re);
                p->count++;
            }
            a = b + 1;
        }
    }
    fclose(f);
    ck_assert_msg(rows > 10 && p->count > 20, "%s: no buffer-name table (%d rows, %d names)", DESIGN_MD, rows,
                  p->count);
}

static void patterns_free(patterns *p)
{
    for (int i = 0; i < p->count; i++)
        regfree(&p->re[i]);
}

static int matches(const char *re_src, const char *name)
{
    regex_t re;
    ck_assert(regcomp(&re, re_src, REG_EXTENDED | REG_NOSUB) == 0);
    int m = regexec(&re, name, 0, NULL, 0) == 0;
    regfree(&re);
    return m;
}

/* Whether `name` is a design part name (0) or a listed exception (1 + its index), or neither (-1). */
static int classify(const patterns *p, const char *name)
{
    for (int i = 0; i < p->count; i++)
        if (regexec(&p->re[i], name, 0, NULL, 0) == 0)
            return 0;
    for (int i = 0; i < NOT_IN_DESIGN; i++)
        if (matches(not_in_design[i], name))
            return 1 + i;
    return -1;
}

/* Checks every name entry o of a table can produce; marks the exceptions used. Returns the
 * number of names checked. */
static int check_entry(const patterns *p, const char *what, const pass_output *o, int *used)
{
    static const int faces[] = {1, 6};
    int checked = 0;
    for (int m = 0; m < ind_method_count(); m++)
        for (int fi = 0; fi < 2; fi++)
            for (int level = 0; level < 3; level++) {
                pass_output_at at = {3, faces[fi], faces[fi] - 1, level, ind_method_at(m)->prefix};
                char name[96];
                ck_assert_msg(pass_output_name(o, &at, name, sizeof name) == 0, "%s: %s does not expand", what,
                              o->name);
                ck_assert_msg(strpbrk(name, "<>[]{}") == NULL, "%s: %s leaves %s", what, o->name, name);
                int c = classify(p, name);
                ck_assert_msg(c >= 0, "%s: %s (from %s) is no part name of %s's buffer-name table", what, name,
                              o->name, DESIGN_MD);
                if (c > 0)
                    used[c - 1] = 1;
                checked++;
            }
    return checked;
}

START_TEST(names_in_design)
{
    patterns p;
    design_patterns(&p);
    int used[NOT_IN_DESIGN] = {0}, checked = 0;
    for (size_t t = 0; t < sizeof tables / sizeof tables[0]; t++)
        for (const pass_output *o = tables[t].table; o->name; o++)
            checked += check_entry(&p, tables[t].what, o, used);
    for (int m = 0; m < SHADOW_METHOD_COUNT; m++)
        for (const pass_output *o = shadow_methods[m]->outputs; o && o->name; o++)
            checked += check_entry(&p, shadow_methods[m]->name, o, used);
    ck_assert_int_gt(checked, 0);
    for (int i = 0; i < NOT_IN_DESIGN; i++)
        ck_assert_msg(used[i], "not_in_design[%d] (%s) matches no table's name: drop it", i, not_in_design[i]);
    patterns_free(&p);
}
END_TEST

/* The patterns reject what the design does not name, so names_in_design can fail. */
START_TEST(wrong_names_rejected)
{
    patterns p;
    design_patterns(&p);
    static const char *const wrong[] = {"gbuffer.positon", "shadow.light.face0", "lightgbuffer.light0.face1.depth",
                                        "upsample.levelx", "composite", "direct.radiance.extra"};
    for (size_t i = 0; i < sizeof wrong / sizeof wrong[0]; i++)
        ck_assert_msg(classify(&p, wrong[i]) < 0, "%s was accepted", wrong[i]);
    static const char *const right[] = {"gbuffer.position", "shadow.light0.face5", "shadow.light2",
                                        "lightgbuffer.light1.face0.albedo", "bounce.light0", "atrous.scale3",
                                        "stability.final.display", "multiimage.map0.face1.material"};
    for (size_t i = 0; i < sizeof right / sizeof right[0]; i++)
        ck_assert_msg(classify(&p, right[i]) == 0, "%s was rejected", right[i]);
    patterns_free(&p);
}
END_TEST

/* Entries are well formed: channels named, picks within RGBA, CPU entries pick nothing. */
START_TEST(entries_well_formed)
{
    for (size_t t = 0; t < sizeof tables / sizeof tables[0]; t++)
        for (const pass_output *o = tables[t].table; o->name; o++) {
            int n = pass_output_channels(o);
            ck_assert_msg(n >= 1, "%s: %s has no channels", tables[t].what, o->name);
            if (o->attachment == PASS_OUT_CPU)
                continue;
            ck_assert_msg(o->attachment >= 0 && o->attachment < 8, "%s: %s", tables[t].what, o->name);
            ck_assert_msg(n <= 4, "%s: %s reads %d channels of an RGBA attachment", tables[t].what, o->name, n);
            for (int c = 0; c < n; c++)
                ck_assert_msg(o->pick[c] >= 0 && o->pick[c] < 4, "%s: %s", tables[t].what, o->name);
        }
}
END_TEST

/* pass_output_name fills the placeholders as the frame loop names its buffers. */
START_TEST(name_expansion)
{
    char name[96];
    const pass_output shadow = {.name = "shadow.light<i>[.face<f>].blocker"};
    pass_output_at one = {2, 1, 0, 0, NULL}, cube = {1, 6, 4, 0, NULL};
    ck_assert_int_eq(pass_output_name(&shadow, &one, name, sizeof name), 0);
    ck_assert_str_eq(name, "shadow.light2.blocker");
    ck_assert_int_eq(pass_output_name(&shadow, &cube, name, sizeof name), 0);
    ck_assert_str_eq(name, "shadow.light1.face4.blocker");
    const pass_output scale = {.name = "atrous.scale<k>", .level_offset = 1};
    pass_output_at it = {0, 1, 0, 2, NULL};
    ck_assert_int_eq(pass_output_name(&scale, &it, name, sizeof name), 0);
    ck_assert_str_eq(name, "atrous.scale3");
    const pass_output count = {.name = "<m>.count"};
    pass_output_at m = {0, 1, 0, 0, "splat"};
    ck_assert_int_eq(pass_output_name(&count, &m, name, sizeof name), 0);
    ck_assert_str_eq(name, "splat.count");
    ck_assert_int_eq(pass_output_name(&count, &m, name, 8), -1); /* does not fit */
    const pass_output bad = {.name = "x.<q>"};
    ck_assert_int_eq(pass_output_name(&bad, &m, name, sizeof name), -1);
}
END_TEST

int main(void)
{
    Suite *su = suite_create("outputs");
    TCase *tc = tcase_create("tables");
    tcase_add_test(tc, names_in_design);
    tcase_add_test(tc, wrong_names_rejected);
    tcase_add_test(tc, entries_well_formed);
    tcase_add_test(tc, name_expansion);
    suite_add_tcase(su, tc);
    SRunner *sr = srunner_create(su);
    srunner_run_all(sr, CK_NORMAL);
    int failed = srunner_ntests_failed(sr);
    srunner_free(sr);
    return failed ? EXIT_FAILURE : EXIT_SUCCESS;
}
