/* lineage.h — pixel lineage: for one eye pixel of one recorded frame, everything
 * that made it: the G-buffer sample; per light the shadow-map texel it was tested against
 * (projected with that light's matrices from the manifest's "lights") and the verdict; every
 * photon whose kernel covers the pixel's surface point, with its origin (photons.origin) and
 * its contribution by the engine's own kernel (eng_photon_contribution); the value at the
 * pixel's coordinate in every other buffer (subsampled levels scaled, light-space buffers
 * through the light's matrices); and the same surface point followed across frames by the
 * motion vectors. Used by `ispm lineage` and the viewer's probe. No GL. */
#ifndef ISPM_LINEAGE_H
#define ISPM_LINEAGE_H

#include "eng_core.h"

#include <stddef.h>

/* What lineage reads of a run's manifest.json besides the frame files. */
typedef struct lin_frame_meta {
    int has_camera;
    float view_proj[16], eye[3];
    int light_count;
    eng_light_record lights[ENG_MAX_LIGHT_RECORDS];
} lin_frame_meta;

typedef struct lin_manifest {
    int width, height, frame_count;
    char indirect[32];        /* settings.indirect ("ispm", "kd-gather", ...) */
    float compression;        /* settings.normal_compression */
    float shadow_bias;
    int pcf_radius;
    lin_frame_meta *frames;   /* frame_count */
} lin_manifest;

/* Reads RUN/manifest.json's resolution, settings and per-frame camera and lights. Bad input
 * is ENG_ERR_INVALID / ENG_ERR_PARSE naming the file. Free with lin_manifest_free. */
eng_result lin_manifest_read(const char *run_dir, lin_manifest *m, eng_error *err);
void lin_manifest_free(lin_manifest *m);

/* One frame's inputs: its decoded buffers and manifest entry. */
typedef struct lin_frame {
    const eng_buffer *bufs;
    int count;
    const lin_manifest *m;
    const lin_frame_meta *meta;
} lin_frame;

/* Light l's shadow test at the pixel, as shaders/shadow_pcf.glsl makes it. */
typedef struct lin_shadow {
    int light, face, outside;  /* outside: the lookup left a spot frustum / ortho box */
    char map[64];              /* the shadow buffer's name */
    float uv[2];               /* GL map coordinates of the normal-offset point */
    int texel[2];              /* the centre tap, in the buffer's pixels (row 0 at the top) */
    float distance;            /* the pixel's distance to the light (or depth along it) */
    float compared;            /* the value compared: that of the normal-offset point */
    float stored;              /* the map's value at the centre tap */
    float tolerance;           /* the texel's world size there: lit when compared <= stored + it */
    int lit;                   /* the centre tap's verdict */
    float visibility;          /* the PCF result over (2·pcf_radius + 1)² taps */
} lin_shadow;

/* One photon whose kernel covers the pixel's surface point. */
typedef struct lin_photon {
    int index;                 /* its pixel in photons.map (row-major) */
    float position[3], power[3], density;
    int bounce;
    int light, face, texel[2]; /* photons.origin: the bounce-map texel its path left from */
    float radius;
    float contribution[3];     /* f Φ κ (radiance) or Φ κ (irradiance) */
    float glossy[3];           /* irradiance mode: f_glossy Φ κ */
} lin_photon;

/* The value of a buffer at the pixel's coordinate in that buffer. */
typedef struct lin_value {
    const char *name;          /* the buffer's (borrowed from the frame) */
    int x, y;
    int channel_count;
    const char *const *channels;
    float v[8];                /* the first 8 channels */
} lin_value;

typedef struct lin_result {
    int x, y, covered;         /* covered: a surface (gbuffer.depth > 0) */
    float position[3], normal[3], albedo[3], material[4], depth, motion[2];
    int shadow_count;
    lin_shadow shadows[ENG_MAX_LIGHT_RECORDS];
    /* Photons: has_photons = photons.map and photons.origin present and the method's kernel
     * is the photon-volume kernel (not "quads"); why says otherwise. */
    int has_photons;
    const char *why;
    int map_photons;           /* photons in the map */
    int photon_count;
    lin_photon *photons;
    int irradiance;            /* the indirect buffer is <prefix>.irradiance */
    const char *splat_name;    /* <prefix>.indirect / .irradiance, NULL if absent */
    /* has_splat: splat and splat_count hold its values at (splat_x, splat_y), the photons were
     * evaluated at that pixel's surface point: the eye pixel's when the buffer has the eye
     * resolution (splat_level 0), else the subsampled level's whose G-buffer
     * (gbuffer.level<k>.position, .normal, .depth) has the buffer's size (splat_covered: a
     * surface there). */
    int has_splat, splat_level, splat_x, splat_y, splat_covered;
    float splat[3], splat_count;
    float splat_position[3], splat_normal[3];
    double sum[3];             /* Σ contributions (double) */
    int value_count;
    lin_value *values;         /* every other eye-space buffer and the light-space buffers */
} lin_result;

/* The lineage of pixel (x, y) of frame fr. ENG_ERR_INVALID when the pixel is outside the image
 * or the frame lacks the G-buffer. */
eng_result lin_pixel(const lin_frame *fr, int x, int y, lin_result *out, eng_error *err);
void lin_result_free(lin_result *r);

/* The buffer named name in fr, or NULL. */
const eng_buffer *lin_find(const lin_frame *fr, const char *name);

/* The channels named in csv ("R,G,B", at most 8) of b at (x, y) into out, found by name (EXR
 * files keep channels sorted by name). Returns 0, out partly unset, when b is NULL, (x, y)
 * outside or a channel missing. */
int lin_read_named(const eng_buffer *b, int x, int y, const char *csv, float *out);

/* Where (x, y) of a w×h eye image falls in a bw×bh buffer (a subsampled level): the pixel
 * whose area holds the eye pixel's centre. */
void lin_scale(int x, int y, int w, int h, int bw, int bh, int *bx, int *by);

/* The eye pixel of the same surface point in the previous frame: (x, y) + gbuffer.motion,
 * rounded from the pixel's centre. Returns 0 when it leaves the image or the pixel has no
 * surface. */
int lin_follow_back(const lin_frame *fr, int x, int y, int *px, int *py);

/* The pixel of frame `next` whose motion leads back to (x, y) of the frame before it: the one
 * within `window` pixels whose centre + motion lands nearest (x, y)'s centre, if within a pixel.
 * Returns 0 if none. */
int lin_follow_forward(const lin_frame *next, int x, int y, int window, int *nx, int *ny);

#endif
