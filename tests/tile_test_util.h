/* tile_test_util.h — what the suites that render and compare methods share (test_tilegather.c,
 * test_tilegather_gl.c, test_aniso.c, test_finalgather.c): keeping the buffers a render
 * announces, and rendering one frame of a sequence file with extra settings. Test-only,
 * included by one suite each (static functions). */
#ifndef ISPM_TILE_TEST_UTIL_H
#define ISPM_TILE_TEST_UTIL_H

#include "eng.h"

#include <check.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

typedef struct kept {
    char name[96];
    int w, h, n;
    float *data;
} kept;

#define KEEPER_MAX 96

typedef struct keeper {
    int all; /* 1: keep every buffer; 0: the gathers', indirect.radiance and photons.map */
    int count;
    kept bufs[KEEPER_MAX];
} keeper;

/* Keeps what the methods produce (and the photon map, to check both gathered the same). */
static int keep_buffer(void *user, int frame, const eng_buffer *b)
{
    (void)frame;
    keeper *k = user;
    if (!k->all && strncmp(b->name, "gather.", 7) && strcmp(b->name, "indirect.radiance") &&
        strcmp(b->name, "photons.map"))
        return 0;
    ck_assert_int_lt(k->count, KEEPER_MAX);
    kept *d = &k->bufs[k->count++];
    snprintf(d->name, sizeof d->name, "%s", b->name);
    d->w = b->width;
    d->h = b->height;
    d->n = b->channel_count;
    size_t sz = (size_t)b->width * b->height * b->channel_count * sizeof(float);
    d->data = malloc(sz);
    memcpy(d->data, b->data, sz);
    return 0;
}

static const kept *find(const keeper *k, const char *name)
{
    for (int i = 0; i < k->count; i++)
        if (!strcmp(k->bufs[i].name, name))
            return &k->bufs[i];
    return NULL;
}

static void keeper_clear(keeper *k)
{
    for (int i = 0; i < k->count; i++)
        free(k->bufs[i].data);
    memset(k, 0, sizeof *k);
}

/* Renders `frame` of the sequence file `rel` (under the source tree) with extra settings
 * (a JSON fragment inserted at the front of its settings object) into k. */
#if defined(__GNUC__)
__attribute__((unused)) /* a suite may render its own way (test_finalgather.c sizes its images) */
#endif
static void render(const char *rel, const char *settings, int frame, keeper *k)
{
    char path[1024];
    snprintf(path, sizeof path, "%s/%s", ISPM_SOURCE_DIR, rel);
    FILE *f = fopen(path, "rb");
    ck_assert_msg(f != NULL, "%s", path);
    static char text[65536], json[70000];
    size_t len = fread(text, 1, sizeof text - 1, f);
    fclose(f);
    text[len] = 0;
    char *at = strstr(text, "\"settings\"");
    ck_assert(at != NULL);
    at = strchr(at, '{');
    ck_assert(at != NULL);
    snprintf(json, sizeof json, "%.*s%s, %s", (int)(at + 1 - text), text, settings, at + 1);
    seq_sequence *seq = calloc(1, sizeof *seq);
    eng_error err;
    ck_assert_msg(seq_parse(path, json, strlen(json), seq, &err) == ENG_OK, "%s", err.msg);
    scn_scene *scene = NULL;
    ck_assert_msg(scn_load_gltf(seq->scene_path, &scene, &err) == ENG_OK, "%s", err.msg);
    eng_engine *eng = NULL;
    eng_desc d = {.scene = scene, .sequence = seq};
    ck_assert_msg(eng_create(&d, &eng, &err) == ENG_OK, "%s", err.msg);
    eng_listener l = {k, NULL, keep_buffer, NULL};
    ck_assert_int_eq(eng_add_listener(eng, &l), ENG_OK);
    ck_assert_msg(eng_render_frame(eng, frame, &err) == ENG_OK, "%s", err.msg);
    eng_destroy(eng);
    scn_destroy(scene);
    free(seq);
}

#endif
