/* seq.h — the sequence file (JSON): which scene, how many frames at what rate, resolution,
 * camera, engine settings and what to capture. */
#ifndef ISPM_SEQ_H
#define ISPM_SEQ_H

#include "scn.h"

#ifdef __cplusplus
extern "C" {
#endif

#define SEQ_MAX_CAPTURE 32
#define SEQ_MAX_CAMKEYS 64
#define SEQ_MAX_LIGHTS 8
#define SEQ_MAX_ANIMATIONS 32
/* The direction a framing camera looks along when the sequence names none (normalised when
 * parsed): at the model's front (+Z in glTF), a little from above and from the right. */
#define SEQ_FRAME_DIRECTION {-0.35f, -0.3f, -1.0f}

/* A light the sequence adds to the scene's own ("lights"): a root node at position whose
 * -Z axis points along direction (spot, directional), carrying this light. */
typedef struct seq_light {
    scn_light light;
    float position[3];  /* default (0,0,0) */
    float direction[3]; /* default (0,0,-1); normalised */
} seq_light;

/* One entry of "animations": a glTF animation by name (name[0] != 0) or by index. */
typedef struct seq_animation {
    char name[SCN_NAME_MAX];
    int index;
} seq_animation;

typedef struct seq_camera_key {
    double time;
    float position[3];
    float target[3];
} seq_camera_key;

typedef struct seq_sequence {
    char path[4096];        /* the sequence file */
    char scene_path[4096];  /* resolved relative to the sequence file's folder */
    char name[SCN_NAME_MAX];
    int frame_count;        /* >= 1 */
    double fps;             /* > 0; frame i is at t = i / fps */
    int still;              /* "still": true: every frame at t = 0 (a still view, e.g. for
                             * progressive accumulation); default 0 */
    int width, height;      /* pixels, 1..16384 */
    /* Camera: either a glTF camera node (camera_node[0] != 0) or explicit look-at keys,
     * linearly interpolated and clamped (camera_key_count >= 1). */
    char camera_node[SCN_NAME_MAX];
    int camera_by_index;    /* {"node": <index>}: camera_node_index is a glTF node index */
    int camera_node_index;
    int camera_key_count;
    seq_camera_key camera_keys[SEQ_MAX_CAMKEYS];
    float camera_up[3];     /* look-at keys only; default (0,1,0) */
    float camera_yfov;      /* radians; look-at keys only; default 40° */
    float camera_znear, camera_zfar; /* defaults 0.05, 100 */
    /* No "camera", or {"frame": "scene"}: the camera frames the scene's bounds at t = 0
     * (seq_frame_scene) looking along camera_direction (normalised), with camera_up and
     * camera_yfov; the engine fills the key and the planes from the loaded scene. */
    int camera_frame;
    float camera_direction[3];
    eng_settings settings;
    /* Glob patterns (fnmatch) of buffer names to capture; none means "*". */
    int capture_count;
    char capture[SEQ_MAX_CAPTURE][SCN_NAME_MAX];
    char digest[40];        /* hex XXH3-128 of the sequence file bytes */
    /* What of the glTF is played: "scene_index" (which of its scenes, when has_scene_index;
     * else the default), "animations" (when has_animations; else all of them) and "lights"
     * added to its own. Zero-initialised fields mean the glTF's defaults. */
    int has_scene_index, scene_index;
    int has_animations, animation_count;
    seq_animation animations[SEQ_MAX_ANIMATIONS];
    int light_count;
    seq_light lights[SEQ_MAX_LIGHTS];
} seq_sequence;

/* Parses and validates a sequence file. Unknown keys are errors (a typo must not silently
 * fall back to a default). */
eng_result seq_load(const char *path, seq_sequence *out, eng_error *err);
/* Same, from memory; path is only used in messages and to resolve the scene path. */
eng_result seq_parse(const char *path, const char *json, size_t len, seq_sequence *out, eng_error *err);

/* The settings object (JSON text) that `"preset"` p expands to, or NULL for none (presets.c).
 * The parser applies it before the sequence's own keys, which override it; the manifest then
 * records the preset and every setting as expanded. */
const char *seq_preset_settings(eng_preset p);

/* Loads the sequence's scene (seq->scene_path) as the sequence chooses it: its glTF scene
 * scene_index, only the animations it names (an unknown name or index is ENG_ERR_INVALID),
 * its lights added as root nodes after the glTF's, and a warning when the result has no
 * light at all (every frame would be black). The one way the tools load a sequence's scene. */
eng_result seq_load_scene(const seq_sequence *seq, scn_scene **out, eng_error *err);

/* The look-at key and planes of a framing camera (camera_frame): the target is the centre of
 * the bounding box of every drawn vertex at t = 0 (rest pose: skins and morph targets not
 * applied), the eye as far back along camera_direction as the bounding sphere needs to fit
 * the vertical and horizontal field of view, znear and zfar around that sphere. */
void seq_frame_scene(const seq_sequence *seq, const scn_scene *scene, seq_camera_key *key, float *znear,
                     float *zfar);

/* Does the sequence ask for this buffer to be captured? */
int seq_wants(const seq_sequence *seq, const char *buffer_name);
/* The scene time of frame i: i / fps, or 0 for a still sequence. */
double seq_frame_time(const seq_sequence *seq, int frame);

#ifdef __cplusplus
}
#endif

#endif
