/* test_gltf_ext.c — Check suite for what real glTF files bring beyond the core: refusals by
 * name before tinygltf reads anything (glTF 1.0, required extensions), a scene without
 * geometry refused, images decoded only where a drawn material uses them, EXT_texture_webp
 * with its fallback, KHR_materials_unlit, KHR_materials_pbrSpecularGlossiness,
 * KHR_materials_transmission's texture, meshopt-compressed buffer views, the framing camera
 * of sequences without one, and data the validator passes: zero-length normals, indices
 * accessors without bufferView, files that name no mesh.
 * Every glTF is written here, a floor quad with UVs in a data URI. */
#include "seq.h"

#include <check.h>
#include <meshoptimizer.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* 4 positions (a 2 m floor at y = 0), 4 UVs, 6 unsigned short indices: 92 bytes. */
#define FLOOR_B64                                                                                                      \
    "AACAvwAAAAAAAIC/AACAPwAAAAAAAIC/AACAPwAAAAAAAIA/AACAvwAAAAAAAIA/AAAAAAAAAAAAAIA/AAAAAAAAgD8AAIA/AAAAAAAAgD8AAAIAAQ" \
    "AAAAMAAgA="
/* 2x2 images made with ImageMagick: a red PNG, a lossless green WebP, a grey (64/255) PNG. */
#define RED_PNG "data:image/png;base64,iVBORw0KGgoAAAANSUhEUgAAAAIAAAACAQMAAABIeJ9nAAAAA1BMVEX/AAAZ4gk3AAAADElEQVQI12NgYGAAAAAEAAEnNCcKAAAAAElFTkSuQmCC"
#define GREEN_WEBP "data:image/webp;base64,UklGRhwAAABXRUJQVlA4TA8AAAAvAUAAAAfQ/4j+ByKi/wEA"
#define GREY_PNG "data:image/png;base64,iVBORw0KGgoAAAANSUhEUgAAAAIAAAACCAAAAABX3VL4AAAADklEQVQI12N0YGBiYAAAAVIAREsc4IUAAAAASUVORK5CYII="
#define BAD_PNG "data:image/png;base64,AAAAAAAA"

/* A floor glTF: extra members for the root (after a comma), the first node, the primitive's
 * material, materials, textures and images (each a JSON array body, may be empty). */
static char *floor_gltf(const char *root_extra, const char *node, const char *materials, const char *textures,
                        const char *images)
{
    size_t n = 4096 + strlen(root_extra) + strlen(materials) + strlen(textures) + strlen(images);
    char *j = malloc(n);
    ck_assert_ptr_nonnull(j);
    snprintf(j, n,
             "{\"asset\":{\"version\":\"2.0\"},\"scenes\":[{\"nodes\":[0]}],\"nodes\":[%s],"
             "\"meshes\":[{\"primitives\":[{\"attributes\":{\"POSITION\":0,\"TEXCOORD_0\":1},\"indices\":2%s}]}],"
             "\"accessors\":[{\"bufferView\":0,\"componentType\":5126,\"count\":4,\"type\":\"VEC3\","
             "\"min\":[-1,0,-1],\"max\":[1,0,1]},"
             "{\"bufferView\":1,\"componentType\":5126,\"count\":4,\"type\":\"VEC2\"},"
             "{\"bufferView\":2,\"componentType\":5123,\"count\":6,\"type\":\"SCALAR\"}],"
             "\"bufferViews\":[{\"buffer\":0,\"byteLength\":48},{\"buffer\":0,\"byteOffset\":48,\"byteLength\":32},"
             "{\"buffer\":0,\"byteOffset\":80,\"byteLength\":12}],"
             "\"buffers\":[{\"byteLength\":92,\"uri\":\"data:application/octet-stream;base64," FLOOR_B64 "\"}],"
             "\"materials\":[%s],\"textures\":[%s],\"images\":[%s]%s}",
             node, materials[0] ? ",\"material\":0" : "", materials, textures, images, root_extra);
    return j;
}

static eng_result load(const char *json, scn_scene **s, eng_error *err)
{
    *s = NULL;
    memset(err, 0, sizeof *err);
    return scn_load_gltf_memory("test.gltf", json, strlen(json), s, err);
}

static int has_warning(const scn_scene *s, const char *part)
{
    for (uint32_t i = 0; i < s->warning_count && i < SCN_MAX_WARNINGS; i++)
        if (strstr(s->warnings[i], part))
            return 1;
    return 0;
}

START_TEST(gltf1_refused_by_name)
{
    static const char *const files[] = {
        "{\"asset\":{\"version\":\"1.0\"},\"meshes\":{\"m\":{}}}",
        "{\"meshes\":{\"box\":{\"primitives\":[]}},\"nodes\":{\"n\":{}}}",
        "{\"asset\":{\"version\":\"3.0\"}}",
        "{\"asset\":{\"version\":\"2.0\",\"minVersion\":\"2.1\"}}",
    };
    static const char *const want[] = {"glTF 1.0 (asset.version)", "glTF 1.0 (objects keyed by name",
                                       "glTF 3.0 (asset.version)", "asset.minVersion 2.1"};
    for (size_t i = 0; i < sizeof files / sizeof files[0]; i++) {
        scn_scene *s;
        eng_error err;
        ck_assert_int_eq(load(files[i], &s, &err), ENG_ERR_UNSUPPORTED);
        ck_assert_msg(strstr(err.msg, want[i]) && strstr(err.msg, "test.gltf: "), "%s", err.msg);
        ck_assert_ptr_null(strchr(err.msg, '\n'));
    }
    /* a GLB container of version 1 */
    unsigned char glb[20] = {'g', 'l', 'T', 'F', 1, 0, 0, 0, 20, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0};
    scn_scene *s;
    eng_error err = {{0}};
    ck_assert_int_eq(scn_load_gltf_memory("v1.glb", glb, sizeof glb, &s, &err), ENG_ERR_UNSUPPORTED);
    ck_assert_msg(strstr(err.msg, "version 1 (glTF 1.0)"), "%s", err.msg);
}
END_TEST

START_TEST(required_extension_named_first)
{
    /* The buffer has an empty URI: tinygltf alone would fail on that, not on the extension. */
    const char *j = "{\"asset\":{\"version\":\"2.0\"},\"extensionsRequired\":[\"KHR_lights_punctual\","
                    "\"ACME_magic_compression\"],\"buffers\":[{\"byteLength\":4,\"uri\":\"\"}]}";
    scn_scene *s;
    eng_error err;
    ck_assert_int_eq(load(j, &s, &err), ENG_ERR_UNSUPPORTED);
    ck_assert_msg(strstr(err.msg, "extensionsRequired: ACME_magic_compression is not supported"), "%s", err.msg);
    /* the extensions read are accepted when required */
    char *f = floor_gltf(",\"extensionsUsed\":[\"KHR_materials_unlit\",\"KHR_materials_pbrSpecularGlossiness\","
                         "\"KHR_materials_emissive_strength\"],\"extensionsRequired\":[\"KHR_materials_unlit\","
                         "\"KHR_materials_pbrSpecularGlossiness\",\"KHR_materials_emissive_strength\"]",
                         "{\"mesh\":0}", "", "", "");
    ck_assert_msg(load(f, &s, &err) == ENG_OK, "%s", err.msg);
    scn_destroy(s);
    free(f);
}
END_TEST

START_TEST(no_geometry_is_an_error)
{
    char *f = floor_gltf("", "{\"name\":\"empty\"}", "", "", "");
    scn_scene *s;
    eng_error err;
    ck_assert_int_eq(load(f, &s, &err), ENG_ERR_INVALID);
    ck_assert_msg(strstr(err.msg, "test.gltf: no geometry"), "%s", err.msg);
    free(f);
}
END_TEST

/* A triangle facing +Z: positions (0,0,0), (1,0,0), (0,1,0), then NORMALs (0,0,2), (0,0,0),
 * (0,0,1) (TRI_B64) or (0,0,1), (NaN,0,0), (0,0,1) (TRI_NAN_B64): 72 bytes. */
#define TRI_B64 "AAAAAAAAAAAAAAAAAACAPwAAAAAAAAAAAAAAAAAAgD8AAAAAAAAAAAAAAAAAAABAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAIA/"
#define TRI_NAN_B64 "AAAAAAAAAAAAAAAAAACAPwAAAAAAAAAAAAAAAAAAgD8AAAAAAAAAAAAAAAAAAIA/AADAfwAAAAAAAAAAAAAAAAAAAAAAAIA/"

/* The triangle glTF: buffer base64, the primitive's extra members, extra accessors (each
 * after a comma). */
static char *tri_gltf(const char *b64, const char *prim_extra, const char *accessors)
{
    size_t n = 2048 + strlen(prim_extra) + strlen(accessors);
    char *j = malloc(n);
    ck_assert_ptr_nonnull(j);
    snprintf(j, n,
             "{\"asset\":{\"version\":\"2.0\"},\"scenes\":[{\"nodes\":[0]}],\"nodes\":[{\"mesh\":0}],"
             "\"meshes\":[{\"primitives\":[{\"attributes\":{\"POSITION\":0,\"NORMAL\":1}%s}]}],"
             "\"accessors\":[{\"bufferView\":0,\"componentType\":5126,\"count\":3,\"type\":\"VEC3\","
             "\"min\":[0,0,0],\"max\":[1,1,0]},"
             "{\"bufferView\":0,\"byteOffset\":36,\"componentType\":5126,\"count\":3,\"type\":\"VEC3\"}%s],"
             "\"bufferViews\":[{\"buffer\":0,\"byteLength\":72}],"
             "\"buffers\":[{\"byteLength\":72,\"uri\":\"data:application/octet-stream;base64,%s\"}]}",
             prim_extra, accessors, b64);
    return j;
}

/* A zero-length normal is data (the validator passes it): it becomes the normal of the
 * triangles at its vertex (+Z here; +Y where they are all degenerate), with one warning. A
 * non-finite normal is still an error. */
START_TEST(zero_normal_filled_in)
{
    char *f = tri_gltf(TRI_B64, "", "");
    scn_scene *s;
    eng_error err;
    ck_assert_msg(load(f, &s, &err) == ENG_OK, "%s", err.msg);
    ck_assert_uint_eq(s->primitive_count, 1);
    const float *n = s->primitives[0].normals;
    for (int v = 0; v < 3; v++)
        ck_assert_msg(n[3 * v] == 0.0f && n[3 * v + 1] == 0.0f && n[3 * v + 2] == 1.0f, "normal %d: %g %g %g", v,
                      (double)n[3 * v], (double)n[3 * v + 1], (double)n[3 * v + 2]);
    ck_assert(has_warning(s, "NORMAL: 1 of 3 normals have zero length"));
    scn_destroy(s);
    free(f);
    f = tri_gltf(TRI_NAN_B64, "", "");
    ck_assert_int_eq(load(f, &s, &err), ENG_ERR_INVALID);
    ck_assert_msg(strstr(err.msg, "NORMAL: accessor 1 element 1 is not finite"), "%s", err.msg);
    free(f);
}
END_TEST

/* An indices accessor without bufferView is all zeros (glTF §3.6.2.1), which tinygltf 2.7
 * refuses: the loader reads it (one degenerate triangle, whose zero normal falls back to +Y).
 * One whose bufferView does not exist is still refused. */
START_TEST(indices_without_buffer_view_are_zeros)
{
    char *f = tri_gltf(TRI_B64, ",\"indices\":2", ",{\"componentType\":5123,\"count\":3,\"type\":\"SCALAR\"}");
    scn_scene *s;
    eng_error err;
    ck_assert_msg(load(f, &s, &err) == ENG_OK, "%s", err.msg);
    const scn_primitive *p = &s->primitives[0];
    ck_assert_uint_eq(p->index_count, 3);
    ck_assert(p->indices[0] == 0 && p->indices[1] == 0 && p->indices[2] == 0);
    ck_assert(p->normals[3] == 0.0f && p->normals[4] == 1.0f && p->normals[5] == 0.0f);
    ck_assert_uint_eq(p->vertex_count, 3);
    scn_destroy(s);
    free(f);
    f = tri_gltf(TRI_B64, ",\"indices\":2",
                 ",{\"bufferView\":7,\"componentType\":5123,\"count\":3,\"type\":\"SCALAR\"}");
    ck_assert_int_eq(load(f, &s, &err), ENG_ERR_INVALID);
    ck_assert_msg(strstr(err.msg, "accessor[2] invalid bufferView"), "%s", err.msg);
    free(f);
}
END_TEST

/* No node names a mesh: the refusal says "no geometry" first, then what tinygltf failed on
 * (buffers without data, as the glTF validator's accessor and buffer test files have). */
START_TEST(no_mesh_refused_before_buffers)
{
    const char *j = "{\"asset\":{\"version\":\"2.0\"},\"accessors\":[{\"bufferView\":0,\"componentType\":5126,"
                    "\"count\":1,\"type\":\"VEC3\"}],\"bufferViews\":[{\"buffer\":0,\"byteLength\":12}],"
                    "\"buffers\":[{\"byteLength\":12}]}";
    scn_scene *s;
    eng_error err;
    ck_assert_int_eq(load(j, &s, &err), ENG_ERR_INVALID);
    ck_assert_msg(strstr(err.msg, "test.gltf: no geometry: no node of the scene draws a triangle; the file also "
                                  "fails to load: an empty URI"), "%s", err.msg);
    ck_assert_ptr_null(strchr(err.msg, '\n'));
    /* the same after tinygltf, for what the loader checks (a camera's yfov) */
    const char *c = "{\"asset\":{\"version\":\"2.0\"},\"cameras\":[{\"type\":\"perspective\",\"perspective\":"
                    "{\"yfov\":4,\"znear\":0.1}}]}";
    ck_assert_int_eq(load(c, &s, &err), ENG_ERR_INVALID);
    ck_assert_msg(strstr(err.msg, "test.gltf: no geometry: no node of the scene draws a triangle; the file also "
                                  "fails to load: camera 0: yfov 4"), "%s", err.msg);
    /* nothing else wrong: no geometry alone */
    ck_assert_int_eq(load("{\"asset\":{\"version\":\"2.0\"},\"nodes\":[{}]}", &s, &err), ENG_ERR_INVALID);
    ck_assert_msg(strstr(err.msg, "test.gltf: no geometry: no node of the scene draws a triangle") &&
                      !strstr(err.msg, "also"), "%s", err.msg);
    /* a node with the mesh: the buffer is the error */
    const char *k = "{\"asset\":{\"version\":\"2.0\"},\"nodes\":[{\"mesh\":0}],\"meshes\":[{\"primitives\":"
                    "[{\"attributes\":{\"POSITION\":0}}]}],\"accessors\":[{\"bufferView\":0,\"componentType\":5126,"
                    "\"count\":3,\"type\":\"VEC3\"}],\"bufferViews\":[{\"buffer\":0,\"byteLength\":36}],"
                    "\"buffers\":[{\"byteLength\":36}]}";
    ck_assert_int_ne(load(k, &s, &err), ENG_OK);
    ck_assert_msg(!strstr(err.msg, "no geometry"), "%s", err.msg);
}
END_TEST

START_TEST(images_decoded_only_where_drawn)
{
    /* material 1 (not drawn) uses image 1, which does not decode: the file loads */
    char *f = floor_gltf("", "{\"mesh\":0}",
                         "{\"pbrMetallicRoughness\":{\"baseColorTexture\":{\"index\":0}}},"
                         "{\"pbrMetallicRoughness\":{\"baseColorTexture\":{\"index\":1}}}",
                         "{\"source\":0},{\"source\":1}", "{\"uri\":\"" RED_PNG "\"},{\"uri\":\"" BAD_PNG "\"}");
    scn_scene *s;
    eng_error err;
    ck_assert_msg(load(f, &s, &err) == ENG_OK, "%s", err.msg);
    ck_assert_uint_eq(s->texture_count, 1);
    ck_assert_float_eq_tol(s->textures[0].texels[0], 1.0f, 1e-6f);
    ck_assert_int_eq(s->materials[1].base_color_tex.texture, -1);
    scn_destroy(s);
    free(f);
    /* drawn, it fails naming the image and its format */
    f = floor_gltf("", "{\"mesh\":0}", "{\"pbrMetallicRoughness\":{\"baseColorTexture\":{\"index\":0}}}",
                   "{\"source\":0}", "{\"uri\":\"" BAD_PNG "\"}");
    ck_assert_int_eq(load(f, &s, &err), ENG_ERR_INVALID);
    ck_assert_msg(strstr(err.msg, "image 0") && strstr(err.msg, "format unknown") && strstr(err.msg, "image/png"),
                  "%s", err.msg);
    free(f);
}
END_TEST

START_TEST(webp_and_its_fallback)
{
    const char *ext = ",\"extensionsUsed\":[\"EXT_texture_webp\"]";
    char *f = floor_gltf(ext, "{\"mesh\":0}", "{\"pbrMetallicRoughness\":{\"baseColorTexture\":{\"index\":0}}}",
                         "{\"source\":0,\"extensions\":{\"EXT_texture_webp\":{\"source\":1}}}",
                         "{\"uri\":\"" RED_PNG "\"},{\"uri\":\"" GREEN_WEBP "\"}");
    scn_scene *s;
    eng_error err;
    ck_assert_msg(load(f, &s, &err) == ENG_OK, "%s", err.msg);
    const float *t = s->textures[s->materials[0].base_color_tex.texture].texels;
    ck_assert_msg(t[0] == 0.0f && t[1] == 1.0f && t[2] == 0.0f, "WebP not used: %g %g %g", t[0], t[1], t[2]);
    scn_destroy(s);
    free(f);
    /* a WebP that does not decode: the fallback, with a warning */
    f = floor_gltf(ext, "{\"mesh\":0}", "{\"pbrMetallicRoughness\":{\"baseColorTexture\":{\"index\":0}}}",
                   "{\"source\":0,\"extensions\":{\"EXT_texture_webp\":{\"source\":1}}}",
                   "{\"uri\":\"" RED_PNG "\"},{\"uri\":\"data:image/webp;base64,UklGRhwAAABXRUJQ\"}");
    ck_assert_msg(load(f, &s, &err) == ENG_OK, "%s", err.msg);
    t = s->textures[s->materials[0].base_color_tex.texture].texels;
    ck_assert(t[0] == 1.0f && t[1] == 0.0f);
    ck_assert(has_warning(s, "fallback source, image 0, is used"));
    scn_destroy(s);
    free(f);
    /* no fallback: an error naming the image */
    f = floor_gltf(ext, "{\"mesh\":0}", "{\"pbrMetallicRoughness\":{\"baseColorTexture\":{\"index\":0}}}",
                   "{\"extensions\":{\"EXT_texture_webp\":{\"source\":0}}}",
                   "{\"uri\":\"data:image/webp;base64,UklGRhwAAABXRUJQ\"}");
    ck_assert_int_eq(load(f, &s, &err), ENG_ERR_INVALID);
    ck_assert_msg(strstr(err.msg, "image 0") && strstr(err.msg, "no fallback"), "%s", err.msg);
    free(f);
}
END_TEST

START_TEST(unlit_is_emission)
{
    char *f = floor_gltf("", "{\"mesh\":0}",
                         "{\"pbrMetallicRoughness\":{\"baseColorFactor\":[0.2,0.4,0.6,0.5],"
                         "\"baseColorTexture\":{\"index\":0}},\"extensions\":{\"KHR_materials_unlit\":{}}}",
                         "{\"source\":0}", "{\"uri\":\"" RED_PNG "\"}");
    scn_scene *s;
    eng_error err;
    ck_assert_msg(load(f, &s, &err) == ENG_OK, "%s", err.msg);
    const scn_material *m = &s->materials[0];
    ck_assert(m->emissive[0] == 0.2f && m->emissive[1] == 0.4f && m->emissive[2] == 0.6f);
    ck_assert(m->base_color[0] == 0.0f && m->base_color[1] == 0.0f && m->base_color[2] == 0.0f);
    ck_assert(m->base_color[3] == 0.5f);
    ck_assert_int_eq(m->emissive_tex.texture, m->base_color_tex.texture);
    ck_assert_int_ge(m->emissive_tex.texture, 0);
    ck_assert(m->metallic == 0.0f && m->transmission == 0.0f);
    scn_destroy(s);
    free(f);
}
END_TEST

START_TEST(spec_gloss_conversion)
{
    float base[4], metallic, roughness;
    /* a dielectric: specular 0.04 grey, metallic 0, base colour the diffuse colour */
    const double d1[4] = {0.5, 0.25, 0.125, 0.75}, s1[3] = {0.04, 0.04, 0.04};
    scn_spec_gloss_to_metal_rough(d1, s1, 0.75, base, &metallic, &roughness);
    ck_assert_float_eq_tol(metallic, 0.0f, 1e-6f);
    ck_assert_float_eq_tol(base[0], 0.5f, 1e-6f);
    ck_assert_float_eq_tol(base[1], 0.25f, 1e-6f);
    ck_assert_float_eq_tol(base[3], 0.75f, 1e-6f);
    ck_assert_float_eq_tol(roughness, 0.25f, 1e-6f);
    /* a metal: black diffuse, a gold specular colour: metallic 1, base colour the specular */
    const double d2[4] = {0, 0, 0, 1}, s2[3] = {1.0, 0.766, 0.336};
    scn_spec_gloss_to_metal_rough(d2, s2, 1.0, base, &metallic, &roughness);
    ck_assert_float_eq_tol(metallic, 1.0f, 1e-6f);
    ck_assert_float_eq_tol(base[1], 0.766f, 1e-5f);
    ck_assert_float_eq_tol(roughness, 0.0f, 1e-6f);
    /* through the loader, with a diffuse texture as the base colour texture */
    char *f = floor_gltf("", "{\"mesh\":0}",
                         "{\"extensions\":{\"KHR_materials_pbrSpecularGlossiness\":{\"diffuseFactor\":[0,0,0,1],"
                         "\"specularFactor\":[1,0.766,0.336],\"glossinessFactor\":0.5,"
                         "\"diffuseTexture\":{\"index\":0},\"specularGlossinessTexture\":{\"index\":0}}}}",
                         "{\"source\":0}", "{\"uri\":\"" RED_PNG "\"}");
    scn_scene *s;
    eng_error err;
    ck_assert_msg(load(f, &s, &err) == ENG_OK, "%s", err.msg);
    ck_assert_float_eq_tol(s->materials[0].metallic, 1.0f, 1e-6f);
    ck_assert_float_eq_tol(s->materials[0].roughness, 0.5f, 1e-6f);
    ck_assert_int_ge(s->materials[0].base_color_tex.texture, 0);
    ck_assert(has_warning(s, "specularGlossinessTexture ignored"));
    scn_destroy(s);
    free(f);
    /* a factor of the wrong length is refused */
    f = floor_gltf("", "{\"mesh\":0}",
                   "{\"extensions\":{\"KHR_materials_pbrSpecularGlossiness\":{\"diffuseFactor\":[0,0,0]}}}", "", "");
    ck_assert_int_eq(load(f, &s, &err), ENG_ERR_INVALID);
    ck_assert_msg(strstr(err.msg, "diffuseFactor has 3 values"), "%s", err.msg);
    free(f);
}
END_TEST

START_TEST(transmission_texture_scales_factor)
{
    char *f = floor_gltf("", "{\"mesh\":0}",
                         "{\"extensions\":{\"KHR_materials_transmission\":{\"transmissionFactor\":1,"
                         "\"transmissionTexture\":{\"index\":0,\"extensions\":{\"KHR_texture_transform\":"
                         "{\"scale\":[2,2]}}}}}}",
                         "{\"source\":0}", "{\"uri\":\"" GREY_PNG "\"}");
    scn_scene *s;
    eng_error err;
    ck_assert_msg(load(f, &s, &err) == ENG_OK, "%s", err.msg);
    ck_assert_float_eq_tol(s->materials[0].transmission, 64.0f / 255.0f, 1e-6f);
    ck_assert(has_warning(s, "transmissionTexture"));
    scn_destroy(s);
    free(f);
    /* a transmissionTexture that is no textureInfo */
    f = floor_gltf("", "{\"mesh\":0}",
                   "{\"extensions\":{\"KHR_materials_transmission\":{\"transmissionTexture\":{\"index\":\"a\"}}}}",
                   "", "");
    ck_assert_int_eq(load(f, &s, &err), ENG_ERR_INVALID);
    ck_assert_msg(strstr(err.msg, "transmissionTexture: not a textureInfo"), "%s", err.msg);
    free(f);
}
END_TEST

static eng_result parse(const char *camera, seq_sequence *q, eng_error *err)
{
    char j[1024];
    snprintf(j, sizeof j, "{\"scene\":\"floor.gltf\",\"frames\":1,\"fps\":1,\"resolution\":[40,20]%s%s}",
             camera[0] ? ",\"camera\":" : "", camera);
    memset(err, 0, sizeof *err);
    return seq_parse("seq.json", j, strlen(j), q, err);
}

START_TEST(framing_camera)
{
    static seq_sequence q;
    eng_error err;
    ck_assert_msg(parse("", &q, &err) == ENG_OK, "%s", err.msg);
    ck_assert_int_eq(q.camera_frame, 1);
    const float *d = q.camera_direction;
    ck_assert_float_eq_tol(d[0] * d[0] + d[1] * d[1] + d[2] * d[2], 1.0f, 1e-6f);
    ck_assert_msg(parse("{\"frame\":\"scene\",\"direction\":[0,0,-2],\"yfov_deg\":60}", &q, &err) == ENG_OK, "%s",
                  err.msg);
    ck_assert(q.camera_direction[2] == -1.0f && q.camera_direction[0] == 0.0f);
    ck_assert_int_eq(parse("{\"frame\":\"box\"}", &q, &err), ENG_ERR_INVALID);
    ck_assert_msg(strstr(err.msg, "camera.frame"), "%s", err.msg);
    ck_assert_int_eq(parse("{\"frame\":\"scene\",\"direction\":[0,0,0]}", &q, &err), ENG_ERR_INVALID);
    ck_assert_int_eq(parse("{\"frame\":\"scene\",\"direction\":[0,1,0]}", &q, &err), ENG_ERR_INVALID);
    ck_assert_msg(strstr(err.msg, "parallel"), "%s", err.msg);
    ck_assert_int_eq(parse("{\"frame\":\"scene\",\"znear\":1}", &q, &err), ENG_ERR_INVALID);
    ck_assert_int_eq(parse("{\"frame\":\"scene\",\"node\":\"c\"}", &q, &err), ENG_ERR_INVALID);

    /* the floor (radius sqrt 2 around the origin), looked at straight down -Z at 60° in a
     * 2:1 image: the vertical field of view is the narrower, distance r / sin 30° */
    ck_assert(parse("{\"frame\":\"scene\",\"direction\":[0,0,-1],\"yfov_deg\":60}", &q, &err) == ENG_OK);
    char *f = floor_gltf("", "{\"mesh\":0,\"translation\":[1,2,3]}", "", "", "");
    scn_scene *s;
    ck_assert_msg(load(f, &s, &err) == ENG_OK, "%s", err.msg);
    seq_camera_key k;
    float zn, zf;
    seq_frame_scene(&q, s, &k, &zn, &zf);
    ck_assert_float_eq_tol(k.target[0], 1.0f, 1e-6f);
    ck_assert_float_eq_tol(k.target[1], 2.0f, 1e-6f);
    ck_assert_float_eq_tol(k.target[2], 3.0f, 1e-6f);
    double dist = sqrt(2.0) / sin(30.0 * 3.14159265358979323846 / 180.0);
    ck_assert_float_eq_tol(k.position[2], (float)(3.0 + dist), 1e-5f);
    ck_assert_float_eq_tol(k.position[0], 1.0f, 1e-6f);
    ck_assert(zn > 0.0f && zn < dist - sqrt(2.0) && zf > dist + sqrt(2.0));
    scn_destroy(s);
    free(f);
}
END_TEST

static void base64(const unsigned char *in, size_t n, char *out)
{
    static const char t[] = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    size_t o = 0;
    for (size_t i = 0; i < n; i += 3) {
        uint32_t v = (uint32_t)in[i] << 16 | (i + 1 < n ? (uint32_t)in[i + 1] << 8 : 0) | (i + 2 < n ? in[i + 2] : 0);
        out[o++] = t[v >> 18 & 63];
        out[o++] = t[v >> 12 & 63];
        out[o++] = i + 1 < n ? t[v >> 6 & 63] : '=';
        out[o++] = i + 2 < n ? t[v & 63] : '=';
    }
    out[o] = 0;
}

/* The floor with its positions and indices compressed by meshoptimizer's encoders (vertex
 * codec, index codec), in a buffer of its own; the views point at a data-less fallback buffer
 * as the extension has them. corrupt: one byte of the vertex stream changed. */
static char *meshopt_floor(const char *ext, int corrupt)
{
    static const float pos[12] = {-1, 0, -1, 1, 0, -1, 1, 0, 1, -1, 0, 1};
    static const unsigned int idx[6] = {0, 2, 1, 0, 3, 2};
    unsigned char enc[1024];
    size_t nv = meshopt_encodeVertexBuffer(enc, sizeof enc, pos, 4, 12);
    ck_assert(nv > 0 && nv < 512);
    size_t at = (nv + 3) & ~(size_t)3;
    size_t ni = meshopt_encodeIndexBuffer(enc + at, sizeof enc - at, idx, 6);
    ck_assert(ni > 0);
    if (corrupt)
        enc[0] ^= 0xFF;
    char b64[2048];
    base64(enc, at + ni, b64);
    char *j = malloc(8192);
    snprintf(j, 8192,
             "{\"asset\":{\"version\":\"2.0\"},\"extensionsUsed\":[\"%s\"],\"extensionsRequired\":[\"%s\"],"
             "\"scenes\":[{\"nodes\":[0]}],\"nodes\":[{\"mesh\":0}],"
             "\"meshes\":[{\"primitives\":[{\"attributes\":{\"POSITION\":0},\"indices\":1}]}],"
             "\"accessors\":[{\"bufferView\":0,\"componentType\":5126,\"count\":4,\"type\":\"VEC3\"},"
             "{\"bufferView\":1,\"componentType\":5123,\"count\":6,\"type\":\"SCALAR\"}],"
             "\"bufferViews\":[{\"buffer\":1,\"byteLength\":48,\"byteStride\":12,\"extensions\":{\"%s\":{\"buffer\":0,"
             "\"byteLength\":%zu,\"byteStride\":12,\"count\":4,\"mode\":\"ATTRIBUTES\"}}},"
             "{\"buffer\":1,\"byteOffset\":48,\"byteLength\":12,\"extensions\":{\"%s\":{\"buffer\":0,\"byteOffset\":%zu,"
             "\"byteLength\":%zu,\"byteStride\":2,\"count\":6,\"mode\":\"TRIANGLES\"}}}],"
             "\"buffers\":[{\"byteLength\":%zu,\"uri\":\"data:application/octet-stream;base64,%s\"},"
             "{\"byteLength\":60,\"extensions\":{\"%s\":{\"fallback\":true}}}]}",
             ext, ext, ext, nv, ext, at, ni, at + ni, b64, ext);
    return j;
}

START_TEST(meshopt_decoded)
{
    static const char *const exts[] = {"EXT_meshopt_compression", "KHR_meshopt_compression"};
    for (int e = 0; e < 2; e++) {
        char *f = meshopt_floor(exts[e], 0);
        scn_scene *s;
        eng_error err;
        ck_assert_msg(load(f, &s, &err) == ENG_OK, "%s", err.msg);
        const scn_primitive *p = &s->primitives[0];
        ck_assert_uint_eq(p->index_count, 6);
        /* The index codec keeps each triangle and its winding, maybe rotated; the loader then
         * un-shares the vertices (no NORMAL: flat normals). Compare corner positions. */
        static const float pos[12] = {-1, 0, -1, 1, 0, -1, 1, 0, 1, -1, 0, 1};
        static const uint32_t want[6] = {0, 2, 1, 0, 3, 2};
        for (int t = 0; t < 2; t++) {
            const float *c[3];
            for (int k = 0; k < 3; k++)
                c[k] = p->positions + 3 * (size_t)p->indices[3 * t + k];
            int rot = -1;
            for (int r = 0; r < 3; r++)
                if (memcmp(c[0], pos + 3 * want[3 * t + r], 3 * sizeof(float)) == 0)
                    rot = r;
            ck_assert_int_ge(rot, 0);
            for (int k = 0; k < 3; k++)
                ck_assert(memcmp(c[k], pos + 3 * want[3 * t + (k + rot) % 3], 3 * sizeof(float)) == 0);
        }
        scn_destroy(s);
        free(f);
        f = meshopt_floor(exts[e], 1);
        eng_result r = load(f, &s, &err);
        ck_assert_int_eq(r, ENG_ERR_INVALID);
        ck_assert_msg(strstr(err.msg, "bufferView 0: ") && strstr(err.msg, exts[e]) && strstr(err.msg, "does not decode"),
                      "%s", err.msg);
        free(f);
    }
}
END_TEST

int main(void)
{
    Suite *s = suite_create("gltf_ext");
    TCase *tc = tcase_create("gltf_ext");
    tcase_set_timeout(tc, 60);
    tcase_add_test(tc, gltf1_refused_by_name);
    tcase_add_test(tc, required_extension_named_first);
    tcase_add_test(tc, no_geometry_is_an_error);
    tcase_add_test(tc, zero_normal_filled_in);
    tcase_add_test(tc, indices_without_buffer_view_are_zeros);
    tcase_add_test(tc, no_mesh_refused_before_buffers);
    tcase_add_test(tc, images_decoded_only_where_drawn);
    tcase_add_test(tc, webp_and_its_fallback);
    tcase_add_test(tc, unlit_is_emission);
    tcase_add_test(tc, spec_gloss_conversion);
    tcase_add_test(tc, transmission_texture_scales_factor);
    tcase_add_test(tc, framing_camera);
    tcase_add_test(tc, meshopt_decoded);
    suite_add_tcase(s, tc);
    SRunner *sr = srunner_create(s);
    srunner_run_all(sr, CK_NORMAL);
    int failed = srunner_ntests_failed(sr);
    srunner_free(sr);
    return failed ? EXIT_FAILURE : EXIT_SUCCESS;
}
