/* eng_internal.h — what the engine's own files share and nobody else sees: small matrix
 * helpers, the GL context and resource helpers, the per-frame view of the scene that the
 * passes draw (eng_frame_scene), and each pass's entry point.
 *
 * Passes take their inputs as arguments and return their outputs (textures owned by the
 * pass object); no pass reaches into another's state. engine.c wires them together and
 * announces every buffer they produce. */
#ifndef ISPM_ENG_INTERNAL_H
#define ISPM_ENG_INTERNAL_H

/* Every GL function is a pointer loaded from the context's backend (glctx.c). */
#include "gl_loader.h"

#include "eng.h"

#define ENG_PI 3.14159265358979323846

/* Defined in the photon section below; the passes take them by pointer. */
typedef struct eng_random_maps eng_random_maps;
typedef struct eng_photon_map eng_photon_map;

/* ---------------------------------------------------------------- math (column-major) */

void m4_identity(float m[16]);
void m4_mul(float out[16], const float a[16], const float b[16]); /* out = a·b; out may alias */
int m4_invert(float out[16], const float m[16]);                  /* 0 if singular */
void m4_perspective(float m[16], float yfov, float aspect, float znear, float zfar);
void m4_look_at(float m[16], const float eye[3], const float target[3], const float up[3]);
void m4_transform_point(const float m[16], const float p[3], float out[3]);
/* Upper 3×3 of the inverse transpose, as a column-major 3×3 (for normals). */
void m4_normal_matrix(float out9[9], const float m[16]);

/* ---------------------------------------------------------------- GL helpers (glutil.c) */

/* Compiles and links vertex + fragment shaders from engine/shaders/<name>; the error names
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

/* ---------------------------------------------------------------- scene as drawn */

typedef struct eng_gpu_prim { /* vertex attribute 5: the previous frame's position */
    GLuint vao, vbo_pos, vbo_nrm, ibo;
    GLuint vbo_uv[2], vbo_col; /* TEXCOORD_0/1 (location 2, 3), COLOR_0 (4); 0 where absent */
    GLsizei index_count;
    GLuint vbo_tan; /* TANGENT xyzw (location 6, normal_map.glsl); 0 where the primitive has none */
} eng_gpu_prim;

/* One draw: a primitive at a node's world transform this frame and the previous one. */
typedef struct eng_draw {
    uint32_t primitive;
    int32_t material;  /* -1 = default material */
    float world[16];
    float prev_world[16];
    const struct eng_gpu_prim *gpu; /* the primitive's buffers, or this draw's deformed copy */
    /* A skinned or morphed draw (deform_gl.c): its vertices this frame in the space `world`
     * maps from (world space, world = identity, when skinned); NULL: the primitive's own. */
    const float *positions, *normals;
    const float *tangents; /* deformed tangents (4 per vertex) beside them, or NULL */
} eng_draw;

/* The object-space positions of draw d (deformed or the primitive's). */
static inline const float *eng_draw_positions(const scn_scene *s, const eng_draw *d)
{
    return d->positions ? d->positions : s->primitives[d->primitive].positions;
}

typedef struct eng_view {
    float view[16], proj[16], view_proj[16];
    float eye[3];
    float znear, zfar;
} eng_view;

typedef struct eng_light_pose {
    scn_light_type type;
    float position[3];  /* world (point, spot) */
    float direction[3]; /* world, unit, where the light points (spot, directional) */
    float radiance_scale[3]; /* colour × intensity: W/sr (point, spot) or W/m² (directional) */
    float range, inner_cone, outer_cone;
    float radius; /* scn_light.radius: sphere radius (m) or disc angular radius (rad); 0 punctual */
} eng_light_pose;

typedef struct eng_frame_scene {
    const scn_scene *scene;
    const eng_gpu_prim *gpu;  /* per scene primitive */
    const GLuint *textures;   /* per scene texture (scn_scene.textures) */
    uint32_t draw_count;
    eng_draw *draws;
    eng_view camera, prev_camera;
    uint32_t light_count;
    eng_light_pose *lights;
    float bounds_min[3], bounds_max[3]; /* world AABB of all geometry this frame */
} eng_frame_scene;

/* Skinned and morphed draws (deform_gl.c, issue 17): per deformed draw its own vertex
 * buffers (positions, normals, previous positions) beside the primitive's texcoords, colours
 * and indices. eng_deform_pose runs after the draws are set for the frame: it deforms each
 * on the CPU at t and at tp (scn_deform), points the draw at the result and at its buffers,
 * sets world/prev_world to identity for skinned ones, and uploads the vertices. */
typedef struct eng_deform eng_deform;
eng_deform *eng_deform_create(const scn_scene *s, const eng_gpu_prim *gpu);
void eng_deform_pose(eng_deform *d, eng_frame_scene *fs, const float *world, const float *prev_world, double t,
                     double tp);
void eng_deform_destroy(eng_deform *d); /* accepts NULL; needs the GL context current */

/* malloc that ends the process with a message when out of memory (engine.c). */
void *eng_xmalloc(size_t size);
/* calloc likewise (n = 0 allocates one element) (engine.c). */
void *eng_xcalloc(size_t n, size_t size);

/* Sets base_color.glsl's uniforms of prog for drawing d with material m: its base colour
 * texture (bound to texture unit ENG_BASE_TEX_UNIT), texcoord set and transform, COLOR_0,
 * and the MASK cutoff. */
#define ENG_BASE_TEX_UNIT 7
void eng_bind_material(GLuint prog, const eng_frame_scene *fs, const eng_draw *d, const scn_material *m);

/* Resolved material values for a draw (the glTF default material for -1). */
scn_material eng_material_of(const scn_scene *scene, int32_t index);
struct rt_hit;
/* The material at a CPU hit: eng_material_of with its base colour times hit->base_tex (the
 * texture and COLOR_0 there), as the G-buffers see it at the same surface point. */
scn_material eng_material_at(const scn_scene *scene, const struct rt_hit *hit);

/* ---------------------------------------------------------------- passes */

/* Eye G-buffer (pass_gbuffer.c). Attachments: 0 position.xyz + coverage in w, 1 normal.xyz,
 * 2 albedo.rgb, 3 (roughness, metallic, transmission, ior), 4 (eye depth, material id,
 * motion x, motion y). Background: zeros, id −1. */
typedef struct pass_gbuffer pass_gbuffer;
eng_result pass_gbuffer_create(int width, int height, pass_gbuffer **out, eng_error *err);
const glu_target *pass_gbuffer_run(pass_gbuffer *p, const eng_frame_scene *fs);
void pass_gbuffer_destroy(pass_gbuffer *p);

/* Shadow maps (pass_shadow.c): per light a 2D array R32F texture holding, for point lights
 * 6 cube faces of distance to the light, for spot lights 1 layer of distance to the light,
 * for directional lights 1 layer of depth along the light direction. */
#define SHADOW_MAX_FACES 6
typedef struct shadow_map {
    glu_target target;
    int faces;
    float view_proj[SHADOW_MAX_FACES][16];
    float far_value; /* what a texel with no geometry holds */
} shadow_map;

/* Half-angle of a spot light's shadow frustum: a little wider than the outer cone, so that
 * the normal offset of a lookup near the cone's edge still lands inside the map. */
static inline float shadow_spot_half_angle(float outer_cone)
{
    float a = outer_cone * 1.05f + 0.02f;
    return a < 1.5f ? a : 1.5f;
}

/* The faces of light l's views (6 cube faces, a spot frustum, or a directional ortho box),
 * their view-projection matrices and the far value, in sm (its target is untouched). The
 * shadow maps, light G-buffers and bounce maps of a light all use these views. */
void light_views(const eng_light_pose *l, const eng_frame_scene *fs, shadow_map *sm);

/* tan of a point light face's or spot frustum's half-angle, or a directional box's
 * half-width: what one texel of a map of `size` texels spans is 2·extent/size. */
float light_view_extent(const eng_light_pose *l, const shadow_map *sm);

typedef struct pass_shadow pass_shadow;
eng_result pass_shadow_create(int size, uint32_t light_count, pass_shadow **out, eng_error *err);
/* Renders light i's map; returns it (owned by the pass). */
const shadow_map *pass_shadow_run(pass_shadow *p, const eng_frame_scene *fs, uint32_t light);
void pass_shadow_destroy(pass_shadow *p);

/* Direct light (pass_direct.c): deferred shading of the G-buffer with all lights and PCF
 * shadow lookups; attachment 0 holds radiance RGB. */
typedef struct pass_direct pass_direct;
eng_result pass_direct_create(int width, int height, pass_direct **out, eng_error *err);
/* extra[l]: light l's shadow-method map (shadow.h; the blocker map of a light with a size). */
/* World size of one shadow texel of light l (u_shadow_texel of shadow_pcf.glsl): per metre of
 * distance for point and spot lights, absolute for directional ones. */
float pass_direct_shadow_texel(const eng_light_pose *l, const shadow_map *sm, const eng_settings *s);
const glu_target *pass_direct_run(pass_direct *p, const eng_frame_scene *fs, const glu_target *gbuf,
                                  const shadow_map *const *shadows, const glu_target *const *extra,
                                  const eng_settings *s);
void pass_direct_destroy(pass_direct *p);

/* Light-space G-buffer (pass_lightgbuffer.c, ISPM §3 step 1b) and bounce map
 * (pass_bounce.c, §4.2), per light, at `size` texels per face: layered targets with one
 * layer per face of light_views. The light G-buffer has 4 attachments (position + coverage,
 * modelled normal, albedo, material); the bounce map 2 (power RGB + ρp, direction + ior). */
typedef struct light_maps {
    shadow_map views;   /* faces and matrices (its target unused) */
    glu_target gbuffer; /* 4 attachments */
    glu_target bounce;  /* 2 attachments */
    int size;
} light_maps;

typedef struct pass_lightmaps pass_lightmaps;
eng_result pass_lightmaps_create(const eng_random_maps *rm, pass_lightmaps **out, eng_error *err);
/* Renders light `light`'s G-buffer and bounce map at size² texels per face into lm
 * (targets are (re)allocated when the size or face count changes). */
typedef struct eng_rmap_frame eng_rmap_frame;
/* rf: how this frame reads the random maps (rmap_frame), the same for the CPU trace. */
eng_result pass_lightmaps_run(pass_lightmaps *p, const eng_frame_scene *fs, uint32_t light, int size,
                              const eng_rmap_frame *rf, light_maps *lm, eng_error *err);
void light_maps_release(light_maps *lm);
void pass_lightmaps_destroy(pass_lightmaps *p);

/* Photon volumes (pass_splat.c, ISPM §5): accumulates Eq. 1 of every photon into an RGBA32F
 * target (RGB radiance, A = number of kernels covering the pixel), depth-tested against the
 * eye G-buffer's depth buffer. */
typedef struct pass_splat pass_splat;
/* irradiance = 0: one attachment, RGB outgoing radiance (splat.frag.glsl). irradiance = 1:
 * for the reconstruction filters, two attachments: 0 irradiance RGB + count, 1 the glossy
 * radiance (splat_irradiance.frag.glsl). width×height must be the G-buffer's it runs against.
 * aniso: NULL, or the anisotropic kernel's 4 floats per photon (indirect.h, ind_input). */
eng_result pass_splat_create(int width, int height, int irradiance, pass_splat **out, eng_error *err);
/* Per-pixel radius scales (w×h, top row first, each ≤ 1) the next pass_splat_run applies to
 * every photon's r_xy and r_z at that pixel (progressive photon mapping's per-pixel radius,
 * progressive.h); NULL: none (the default). */
void pass_splat_set_pixel_scale(pass_splat *p, const float *scale);
/* Grows the pass's CPU arrays to n photons and builds its index data, calling no GL (so the
 * photon stage may call it on the overlap worker once the map's size is known; pass_splat_run
 * grows the GL buffers to match). prefault: touch the new arrays now, so that their page faults
 * are taken on the calling thread rather than when the GL thread fills them. */
void pass_splat_reserve(pass_splat *p, size_t n, int prefault);
/* Uploads w×h scales (top row first) into the R32F texture *tex (created on first use, with
 * *rows its w×h upload scratch): the u_pixel_scale of shaders/pixel_scale.glsl. */
void pixel_scale_upload(GLuint *tex, float **rows, int w, int h, const float *scale);
const glu_target *pass_splat_run(pass_splat *p, const eng_frame_scene *fs, const glu_target *gbuf,
                                 const eng_photon_map *map, const float *radius,
                                 const float *aniso, const eng_settings *s);
void pass_splat_destroy(pass_splat *p);
/* ISPM §5.1 Eq. 2–3 on the CPU, the same kernel shaders/splat.frag.glsl evaluates: d = s − x
 * (surface point minus photon), n_p the photon's surface normal. Returns κ in 1/m²; 0 outside
 * the ellipsoid. Integrates to 1 over the photon's surface plane. */
float splat_kernel(const float d[3], const float n_p[3], float r_xy, float r_z);

/* The kernel radius r_xy of a photon of path density rho (ISPM §2.5/§4.3: large kernels for
 * improbable paths, small for caustics): kernel_radius · clamp((1000 ρ)^(−1/4), 1/4, 2). */
float splat_radius(float kernel_radius, float rho);

/* Where photon volumes can reach the G-buffer (splat_bounds.c): per SPLAT_TILE² tile of the
 * eye G-buffer, the bounding box of its surface points. position: width×height RGBA (xyz, w
 * = coverage; w = 0 pixels are background and left out), GL row order (bottom row first).
 * A zero-initialised splat_tiles is empty; build (re)allocates. */
#define SPLAT_TILE 8
#define SPLAT_COARSE 4 /* tiles per side of a coarse tile */
typedef struct splat_tiles {
    int width, height, tiles_x, tiles_y, coarse_x, coarse_y;
    float *box;    /* per tile, rows bottom first: min xyz, max xyz; min > max without surface */
    float *coarse; /* the same per coarse tile */
} splat_tiles;
void splat_tiles_build(splat_tiles *t, const float *position, int width, int height);
void splat_tiles_free(splat_tiles *t); /* accepts NULL */

/* A photon volume as drawn: inclusive pixel rectangle in GL window coordinates (x right, y up
 * from the bottom row) and the NDC depth of its far side. */
typedef struct splat_bounds {
    int x0, y0, x1, y1;
    float z;
} splat_bounds;
/* Whether the kernel of a photon at x (surface normal n, radii r_xy ≥ r_z) can reach a pixel
 * of t's G-buffer seen through view_proj (proj: its projection part), and if so the
 * rectangle that holds every such pixel (returns 1), else 0. Conservative: every pixel whose
 * G-buffer point lies in the kernel's support (t < 1 in Eq. 2, as the shaders evaluate it in
 * float) is inside the rectangle. */
int splat_photon_bounds(const float view_proj[16], const float proj[16], const splat_tiles *t, const float x[3],
                        const float n[3], float r_xy, float r_z, splat_bounds *out);

/* Reconstruction filters (pass_filter.c; DESIGN.md step 7). G-buffer targets are laid out as
 * pass_gbuffer's: 0 position, 1 normal (w: the point's eye depth in the previous frame),
 * 2 albedo, 3 material, 4 (eye depth, material id, motion x, motion y). Every run returns the
 * pass's own target(s); inputs are textures. */

/* Joint bilateral upsampling by one level (003 §5.2, 004 §6): from a low-resolution G-buffer
 * and its irradiance + glossy textures to hi_gb's resolution. Returns 2 attachments:
 * 0 irradiance (A = weight sum, 0 where the closest-depth tap was taken alone), 1 glossy. */
typedef struct pass_upsample pass_upsample;
eng_result pass_upsample_create(int width, int height, pass_upsample **out, eng_error *err);
const glu_target *pass_upsample_run(pass_upsample *p, const glu_target *lo_gb, GLuint lo_irradiance,
                                    GLuint lo_glossy, const glu_target *hi_gb);
void pass_upsample_destroy(pass_upsample *p);

/* Temporal accumulation (002 §7.2, Eq. 7.3–7.4). Keeps its result and the G-buffer's normal
 * and depth for the next call; the first call after create or reset has no history (α = 0).
 * Returns 2 attachments: 0 result RGB + α in A, 1 the reprojected history RGB. */
typedef struct pass_temporal pass_temporal;
eng_result pass_temporal_create(int width, int height, pass_temporal **out, eng_error *err);
const glu_target *pass_temporal_run(pass_temporal *p, const glu_target *gb, GLuint irradiance, float alpha);
void pass_temporal_reset(pass_temporal *p);
void pass_temporal_destroy(pass_temporal *p);

/* Edge-avoiding À-Trous with variance-clipped details (002 §7.3, Eq. 7.5–7.8), `iterations`
 * iterations (1..8) at steps 1, 2, 4, ... Returns an array of `iterations` targets, one per
 * iteration i, with 4 attachments: 0 S_{i+1}, 1 the kept detail D'_i, 2 Σ_{k≤i} D'_k,
 * 3 S_{i+1} + Σ_{k≤i} D'_k (the last one's is the filter's result). */
typedef struct pass_atrous pass_atrous;
eng_result pass_atrous_create(int width, int height, int iterations, pass_atrous **out, eng_error *err);
const glu_target *pass_atrous_run(pass_atrous *p, const glu_target *gb, GLuint irradiance,
                                  eng_atrous_detail detail, float gamma);
void pass_atrous_destroy(pass_atrous *p);

/* The BSDF applied to reconstructed irradiance (002 §7.4 Eq. 7.9) plus the glossy radiance:
 * outgoing indirect radiance RGB in attachment 0. */
typedef struct pass_resolve pass_resolve;
eng_result pass_resolve_create(int width, int height, pass_resolve **out, eng_error *err);
const glu_target *pass_resolve_run(pass_resolve *p, const glu_target *gb, GLuint irradiance, GLuint glossy);
void pass_resolve_destroy(pass_resolve *p);

/* Composite (pass_composite.c): attachment 0 = direct + indirect + specular + emission
 * (linear radiance), attachment 1 = display transform (exposure, clamp, sRGB encoding).
 * indirect, specular and emission may be 0 (not added). */
typedef struct pass_composite pass_composite;
eng_result pass_composite_create(int width, int height, pass_composite **out, eng_error *err);
const glu_target *pass_composite_run(pass_composite *p, GLuint direct_tex, GLuint indirect_tex,
                                     GLuint specular_tex, GLuint emission_tex, GLuint translucent_tex, const eng_settings *s);
void pass_composite_destroy(pass_composite *p);
/* Indirect light × the A of tex (the eye G-buffer's attachment 5: occlusion textures) from now
 * on; 0: not multiplied (scenes without an occlusion texture). */
void pass_composite_set_occlusion(pass_composite *p, GLuint tex);

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

/* ---------------------------------------------------------------- photons (ISPM §4) */

/* Precomputed random maps (001_… §3.1 PRM; 003_… §4.1 and §6.1 "Random numbers"; 004_… §7):
 * tables made once per run from a fixed seed and never changed, so that a path seeded by the
 * same scene quantity reads the same numbers every frame. Entry k of a path seeded s is
 * table[(s + k) & (size − 1)]. */
typedef struct eng_random_maps {
    uint32_t size;   /* entries per table, a power of two */
    float *uniform;  /* size × 4 uniform numbers in [0,1) */
    float *cosine;   /* size × 4: cosine-weighted hemisphere direction about +Z (x,y,z), pdf */
    float *sphere;   /* size × 4: uniform sphere direction (x,y,z), pdf = 1/4π */
} eng_random_maps;

eng_result rmap_create(uint64_t seed, uint32_t size, eng_random_maps *out, eng_error *err);
void rmap_destroy(eng_random_maps *rm);
/* A 32-bit hash of the exact bits of a position (or any 3 floats) and a salt: the seed of a
 * CPU photon path (ISPM §4.1: "re-seed … with a hash of its world space [position] in the
 * bounce map"). The salt is 0 with random maps, the frame index with per-frame random. */
uint32_t rmap_hash3(const float p[3], uint32_t salt);
/* Same for a light position and a bounce-map pixel (x, y, face): the bounce map's seed. */
uint32_t rmap_hash_pixel(const float light[3], uint32_t x, uint32_t y, uint32_t face, uint32_t salt);
/* Stratified bounces (`"bounce_strata"`, bsdf_strata in bsdf.h): bounce-map texel (x, y) of
 * `face` lies in the 2^log2n-wide block (x, y) >> log2n; *index is its place in the block,
 * (y mod n)·n + x mod n, and *pattern the block's seed, rmap_hash_pixel(light, block, face,
 * strata_salt) with eng_rmap_frame's strata_salt: it depends on nothing but the light, the block,
 * the frame's salt and random_seed, so static parts of a scene keep their photons. The
 * bounce-map shader computes the same. */
void rmap_strata_texel(const float light[3], uint32_t x, uint32_t y, uint32_t face, uint32_t strata_salt, int log2n,
                       uint32_t *index, uint32_t *pattern);

/* How one frame reads the random maps, the same for the bounce-map shader and the CPU trace:
 * the salt of its seeds, and with stratified sampling across frames (002_… §4.2) the
 * Cranley–Patterson offsets of its stratum (bsdf_stratify). */
typedef struct eng_rmap_frame {
    uint32_t salt;     /* 0 = precomputed random maps; frame-dependent for per-frame random */
    int stratified;    /* 1: rotate every event's numbers by offset (bsdf_stratify) */
    float offset[4];   /* per random dimension, in [0,1) */
    int strata_log2;   /* "bounce_strata" = 2^strata_log2 (bsdf_strata); 0 = off */
    uint32_t strata_salt; /* salt of the blocks' patterns (rmap_strata_texel): the frame's salt,
                           * BSDF_STRATA_SALT and random_seed, so that another seed draws other
                           * permutations as well as other jitter */
} eng_rmap_frame;

/* The frame's eng_rmap_frame under settings s (random, stratified_cycle). Stratified: frame f
 * is stratum k = f mod K of a cycle of K = s->stratified_cycle frames, with offsets
 * frac(k·g_d / K) for g = (1, 1, 1, g₃), g₃ the integer coprime to K nearest K/φ: over a cycle
 * every dimension visits the K strata [j/K, (j+1)/K) once, and the direction pair (d = 2, 3)
 * follows a rank-1 (Fibonacci-like) lattice, so it covers the unit square evenly rather than
 * along its diagonal. Offsets are exact multiples of 1/K; frames f and f + K read the same. */
void rmap_frame(const eng_settings *s, int frame, eng_rmap_frame *out);

/* A photon leaving the first bounce (bounce map, ISPM Table 1): outgoing direction and power,
 * at the surface point of the light's G-buffer. Power 0 = absorbed. */
typedef struct eng_bounce_photon {
    float position[3];
    float direction[3]; /* outgoing, unit */
    float power[3];     /* W per channel */
    float path_density; /* ρp so far */
    float ior;          /* index of refraction of the medium the photon travels in */
    int delta;          /* 1: the bounce took a delta lobe (mirror, glass: BSDF_LOBE_MIRROR..REFRACT) */
} eng_bounce_photon;

/* A photon-map photon (ISPM Table 1): stored where a path hits a surface, before it
 * scatters again. */
typedef struct eng_photon {
    float position[3];
    float direction[3]; /* ω_i: unit, from the surface toward where the light came from */
    float power[3];     /* Φ_i, W per channel */
    float normal[3];    /* n_p: shading normal of the surface hit, facing the incoming photon */
    float path_density; /* ρp */
    uint16_t bounce;    /* 2 = second surface of the path (the first stored), 3, ... */
    uint16_t caustic;   /* 1: every scatter before this surface took a delta lobe (a path L S+ D:
                         * the caustic photons of Jensen 1996, which the final gather adds at its
                         * pixels, ind_finalgather.c) */
    float ray_length;   /* length of the ray segment that brought it here (m): 002 Eq. 6.1, 004 §6 */
} eng_photon;

typedef struct eng_photon_map {
    size_t count, capacity;
    eng_photon *photons;
    /* Optional (want_source = 1): per photon the index of the input (bounce-map) photon whose
     * path stored it, for pixel lineage; source_capacity entries allocated. */
    int want_source;
    uint32_t *source;
    size_t source_capacity;
    /* photon_trace's per-thread photon buffers (photon_trace.c), kept from one trace to the
     * next so that a frame reuses the last frame's memory; freed by photon_map_free. */
    struct pt_buf *trace_bufs;
    int trace_buf_count;
    struct pt_path *trace_paths; /* ... and where each path's photons are: trace_path_capacity, */
    size_t trace_path_capacity, trace_path_count; /* the last trace's trace_path_count */
    /* The last trace's rays and photons per batch of inputs (trace_batch_count of them; 0
     * before the first trace): where in the map the next trace puts each batch's photons. */
    struct eng_trace_batch *trace_batches;
    size_t trace_batch_count, trace_batch_capacity;
} eng_photon_map;
typedef struct eng_trace_batch {
    uint32_t rays, photons;
    /* During a trace, where the batch's photons are: PT_IN_MAP, at index `at` of the map (where
     * the last trace's counts put them), or thread `held`'s buffer from index `at` on. */
    uint32_t held;
    size_t at;
} eng_trace_batch;
#define PT_IN_MAP UINT32_MAX

typedef struct eng_trace_settings {
    int max_bounces;     /* optional cap on photons stored per path after the bounce map; 0 = none
                          * (Russian roulette alone ends a path, up to the safety limit) */
    int threads;
    uint32_t salt;       /* 0 = precomputed random maps; frame-dependent for per-frame random */
    int stratified;      /* eng_rmap_frame's: 1 = rotate the numbers by offset */
    float offset[4];
    /* The width of a photon's ray cone (photon_trace.c: its texture level of detail at each
     * hit); the engine passes the kernel's diameter 2·kernel_radius. 0: level 0 only. */
    float footprint;
} eng_trace_settings;

typedef struct eng_trace_stats {
    eng_trace_counts counts;        /* what the bounce-ray method counted (image-space methods) */
    uint64_t emitted;               /* bounce-map photons with power > 0 */
    uint64_t truncated;             /* paths still alive after ENG_PHOTON_MAX_HITS surface hits */
    uint64_t stored[ENG_PHOTON_BOUNCES];        /* photons stored at bounce index b (b = 2..) */
    double stored_power[ENG_PHOTON_BOUNCES][3]; /* their total power per channel */
} eng_trace_stats;

/* A ray hit (rt.c): distance along the unit ray, world position, interpolated shading
 * normal (unit; the material's normal texture applied, scn_normal_at) and Embree's geometric normal (unit), both in world space and NOT oriented
 * toward the ray (the caller does that); the draw's material (−1 = default) and the draw
 * index (= Embree geomID). */
typedef struct rt_hit {
    float t;
    float position[3];
    float normal[3];
    float geom_normal[3];
    int32_t material;
    uint32_t draw;
    /* What the material's base colour is multiplied by here (scn_base_color_at: its
     * texture at the hit's texcoord, COLOR_0); (1,1,1,1) without either. */
    float base_tex[4];
    /* What roughness and metallic are multiplied by here: the metallicRoughness texture's
     * G and B (glTF §3.9.2); 1 without one. */
    float roughness_tex, metallic_tex;
    /* What emissiveFactor is multiplied by here: the emissive texture's RGB (sRGB-decoded,
     * glTF §3.9.3); 1 without one. */
    float emissive_tex[3];
    /* Where on the draw's primitive (rt.c; tri = UINT32_MAX where the tracer does not know,
     * e.g. a multi-image hit): triangle, barycentrics of its vertices 1 and 2, and the
     * triangle's world-space area, for rt_hit_textures' footprint. */
    uint32_t tri;
    float bary[2];
    float world_area;
} rt_hit;

/* Fills hit's base_tex, roughness_tex, metallic_tex and emissive_tex from its material's
 * textures on primitive p at (tri, bary) (hit_textures.c). width ≤ 0: level 0 as each
 * sampler's magFilter says (every CPU lookup before issue 17's mips); width > 0: the ray-cone
 * width over |cos| at the hit (world units), the level chosen from it (scn_texref_at_cone). */
void rt_hit_textures(const scn_scene *scene, const scn_primitive *p, rt_hit *hit, float width);

typedef struct eng_rt eng_rt;
/* Closest hit of the ray org + t·dir, t in [tnear, tfar], dir unit, against the scene as
 * last posed by rt_update. Returns 1 and fills hit, or 0 (hit untouched). Thread-safe. */
int rt_intersect(const eng_rt *rt, const float org[3], const float dir[3], float tnear, float tfar, rt_hit *hit);
/* Whether material m names a texture (base colour, metallic-roughness or emissive): the hits on
 * which the photon trace looks textures up at its footprint (photon_trace.c), and so the hits
 * rt_intersect_untextured leaves to it. One definition for both, which must agree. */
static inline int rt_material_textured(const scn_material *m)
{
    return m->base_color_tex.texture >= 0 || m->metallic_roughness_tex.texture >= 0 || m->emissive_tex.texture >= 0;
}

/* rt_intersect for the photon trace, which looks up a textured material's textures itself at
 * the width of its photons' footprint (photon_trace.c): on a draw whose material names a
 * texture the hit's texture factors are left at 1 (world_area is set), everything else is as
 * rt_intersect returns it. */
int rt_intersect_untextured(const eng_rt *rt, const float org[3], const float dir[3], float tnear, float tfar,
                            rt_hit *hit);
/* rt_intersect_untextured (tfar = ∞) on n ≤ 4 rays at once, one rtcIntersect4 packet:
 * found[i] and hits[i] are what rt_intersect_untextured returns for rays[i], given that Embree
 * answers a packet's rays as it answers them one by one (tracebench checks it on every run). */
typedef struct rt_ray {
    float org[3], dir[3], tnear;
} rt_ray;
void rt_intersect4_untextured(const eng_rt *rt, int n, const rt_ray *rays, rt_hit *hits, int *found);
/* alphaMode BLEND geometry (rt.c, pass_translucent.c) is not seen by rt_intersect and
 * rt_occluded; rt_intersect_blend sees only it (lamps ignored), as rt_intersect does. */
int rt_intersect_blend(const eng_rt *rt, const float org[3], const float dir[3], float tnear, float tfar, rt_hit *hit);
int rt_has_blend(const eng_rt *rt); /* posed at least once with a BLEND draw */
int rt_is_blend(const scn_scene *scene, int32_t material); /* material index → alphaMode BLEND */
/* The lamps of lights with a size (rt.c): the light index of the nearest lamp the ray enters
 * at t in (tmin, tmax), other than light skip (−1: none skipped), with *t; −1 when none. A
 * ray that starts inside a lamp ignores it. rt_intersect returns 0 where a lamp comes first. */
int rt_lamp_hit(const eng_rt *rt, const float org[3], const float dir[3], float tmin, float tmax, int skip,
                float *t);

/* CPU photon trace (photon_trace.c, ISPM §4.3): traces every bounce-map photon with power > 0
 * through the scene posed in rt and fills out (its previous contents are replaced; out may
 * start zeroed) with the photons of every path (at most s->max_bounces per path when that is
 * > 0), in input order and, within a path, in hit order. A path ends by Russian roulette, by
 * leaving the scene, at the cap, or after ENG_PHOTON_MAX_HITS surface hits (counted in
 * stats->truncated). The result is bit-identical for any s->threads. stats (may be NULL)
 * gets the emitted and truncated counts and stored count/power per bounce index. fs->scene
 * resolves the materials of the draws rt was built from. ENG_ERR_INVALID on bad settings
 * (max_bounces outside 0..ENG_PHOTON_MAX_HITS, random maps not created), ENG_ERR_NOMEM when
 * out of memory. */
eng_result photon_trace(const eng_rt *rt, const eng_frame_scene *fs, const eng_random_maps *rm,
                        const eng_bounce_photon *in, size_t count, const eng_trace_settings *s,
                        eng_photon_map *out, eng_trace_stats *stats, eng_error *err);
/* How photon_trace_with finds the next surface of a path (trace_method.h): the closest hit of
 * org + t·dir, t ≥ tnear, dir unit, as rt_intersect reports it (1 and hit filled, or 0), with
 * the method's counts added to *counts (a per-thread accumulator). Must be thread-safe and a
 * pure function of its arguments and the method's per-frame state. */
typedef int (*pt_intersect_fn)(const void *state, const float org[3], const float dir[3], float tnear, rt_hit *hit,
                               eng_trace_counts *counts);
/* Optional, the same on n ≤ PT_LANES rays at once (a method that casts packets): found[i] and
 * hits[i] are what intersect returns for rays[i] alone. With it, photon_trace_with keeps
 * PT_LANES paths in flight per thread and asks for their next surfaces together. */
#define PT_LANES 4
typedef void (*pt_intersect_n_fn)(const void *state, int n, const rt_ray *rays, rt_hit *hits, int *found,
                                  eng_trace_counts *counts);
typedef struct pt_tracer {
    pt_intersect_fn intersect;
    const void *state;
    pt_intersect_n_fn intersect_n; /* NULL: ray by ray, one path after the other */
} pt_tracer;
/* The Embree tracer's intersect: state is the eng_rt; rt_intersect with tfar = ∞. */
int pt_embree_intersect(const void *state, const float org[3], const float dir[3], float tnear, rt_hit *hit,
                        eng_trace_counts *counts);
/* ... and its intersect_n: rt_intersect4_untextured packets of 4. */
void pt_embree_intersect_n(const void *state, int n, const rt_ray *rays, rt_hit *hits, int *found,
                           eng_trace_counts *counts);

/* photon_trace with the bounce rays traced by tr instead of Embree; stats->counts gets the
 * sum of what tr counted. photon_trace(rt, ...) is this with the Embree tracer. */
eng_result photon_trace_with(const pt_tracer *tr, const eng_frame_scene *fs, const eng_random_maps *rm,
                             const eng_bounce_photon *in, size_t count, const eng_trace_settings *s,
                             eng_photon_map *out, eng_trace_stats *stats, eng_error *err);
/* Frees the photons and zeroes the map; accepts a zeroed map. */
void photon_map_free(eng_photon_map *m);
/* Grows m's per-thread trace buffers (for a trace on `threads` threads) and its photon array
 * towards `photons` photons and touches the new memory, so that a first trace does not take
 * those page faults; the trace's results do not depend on it (out of memory: leaves m as is).
 * The frame loop calls it on the overlap worker while the GL thread renders (issue 22 item 3). */
void photon_map_reserve(eng_photon_map *m, int threads, size_t photons);

/* ---------------------------------------------------------------- Embree scene (rt.c) */

typedef struct eng_rt eng_rt;
eng_result rt_create(const scn_scene *scene, int threads, eng_rt **out, eng_error *err);
/* Poses every instance at this frame's world matrices: static geometry is built once,
 * geometry whose matrix changed is re-transformed and refit. */
void rt_update(eng_rt *rt, const eng_frame_scene *fs);
int rt_occluded(const eng_rt *rt, const float a[3], const float b[3]);
void rt_destroy(eng_rt *rt);

/* ---------------------------------------------------------------- for CPU renderers */

/* Irradiance at normal incidence that light l delivers to p (no visibility), the unit
 * direction toward it and the distance (INFINITY for directional): shaders/direct.frag.glsl's
 * light model on the CPU (reference.c; the specular pass shades with it too). Returns 0 when
 * the light delivers nothing there. */
int ref_light_at(const eng_light_pose *l, const float p[3], float wl[3], float *dist, float e[3]);

/* Poses the scene at frame `frame` (t = frame / fps) exactly as eng_render_frame does (world
 * matrices, draws, lights, camera, Embree scene) without rendering anything, and returns the
 * posed scene and the Embree scene (owned by the engine; valid until the next call or
 * eng_render_frame). For CPU renderers that must see what the passes see (reference.c). */
/* Camera ray through (px, py) in pixels from the top-left corner of a width×height image: the
 * inverse of the view-projection (GL: NDC y up, so row 0 is NDC y = +1), from the near to the
 * far plane (*tnear, *tfar along the unit dir), so it sees what the rasteriser sees
 * (reference.c; pass_translucent.c). */
void eng_camera_ray(const double inv_view_proj[16], const float eye[3], int width, int height, double px, double py,
                    float org[3], float dir[3], float *tnear, float *tfar);
void eng_pose(eng_engine *e, int frame, const eng_frame_scene **fs, const eng_rt **rt);
const eng_settings *eng_settings_of(const eng_engine *e);
void eng_image_size(const eng_engine *e, int *width, int *height);

/* k-d tree gather (kdgather.c), the traditional photon mapping baseline (003_… Appendix A):
 * outgoing indirect radiance at each eye G-buffer pixel from the photons of `map` whose
 * kernel reaches the pixel's surface point, with the same kernel (splat_kernel, splat_radius,
 * s->kernel_radius, s->normal_compression) and the same BSDF as shaders/splat.frag.glsl, so
 * that it matches the photon-volume scatter up to float rounding. Inputs are w×h images, top
 * row first: position (x,y,z, coverage; coverage 0 = background), normal (x,y,z), albedo
 * (r,g,b), material (roughness, metallic, transmission, ior). out gets w×h×4 floats: radiance
 * R,G,B and the number of photons whose kernel covers the pixel. Multi-threaded (s->threads),
 * bit-identical for any thread count. */
eng_result kd_gather(const eng_photon_map *map, int w, int h, const float *position, const float *normal,
                     const float *albedo, const float *material, const float eye[3], const eng_settings *s,
                     float *out, eng_error *err);

/* ---------------------------------------------------------------- trace bench (trace_bench.c) */

/* What the photon trace of one frame gets (eng_render_frame's arguments to it). */
typedef struct eng_trace_inputs {
    const eng_rt *rt;
    const eng_frame_scene *fs;
    const eng_random_maps *rm;
    const eng_bounce_photon *in;
    size_t count;
    eng_trace_settings settings;
} eng_trace_inputs;
/* Poses frame `frame`, renders its light G-buffers and bounce maps (announced to the listeners
 * as in eng_render_frame) and fills out with the photon trace's inputs, valid until the next
 * frame. ENG_ERR_INVALID for a frame outside the sequence or without indirect light. */
eng_result eng_frame_trace_inputs(eng_engine *e, int frame, eng_trace_inputs *out, eng_error *err);
/* n rays of RT_RAW_FLOATS floats each (org xyz, dir xyz, tnear; tfar = ∞) cast with nothing but
 * Embree against the scene rt_intersect sees (no lamps, no hit attributes), statically shared
 * among `threads` OpenMP threads: width 1 rtcIntersect1 ray by ray (the raw rate the photon
 * trace is measured against), width 4 rtcIntersect4 on packets of 4 consecutive rays. Returns
 * the hit count; out (n entries, may be NULL) gets each ray's Embree result. */
#define RT_RAW_FLOATS 7
typedef struct rt_raw_hit {
    float t, u, v, ng[3]; /* tfar after the call, barycentrics, unnormalised geometric normal */
    unsigned geom, prim;  /* RTC_INVALID_GEOMETRY_ID: no hit */
} rt_raw_hit;
uint64_t rt_cast_raw(const eng_rt *rt, const float *rays, size_t n, int threads, int width, rt_raw_hit *out);

#endif
