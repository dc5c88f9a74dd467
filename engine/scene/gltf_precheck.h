/* gltf_precheck.h — what is checked on a glTF's bytes before tinygltf parses them, and on an
 * image's header before it is decoded (gltf_precheck.c). C ABI: the shim calls it too. */
#ifndef ISPM_GLTF_PRECHECK_H
#define ISPM_GLTF_PRECHECK_H

#include "eng_core.h"

#include <stddef.h>
#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

/* The largest image side a texture may have (docs/inputs.md): 8192 texels, 256 MiB as RGBA8. */
#define SCN_IMAGE_MAX_SIDE 8192
/* The bounds of an external file's size (a buffer or image beside the glTF): never above the
 * largest file a scene may be, never below what an image of the largest side may take. */
#define SCN_EXTERNAL_MIN ((uint64_t)256 << 20)
#define SCN_EXTERNAL_MAX ((uint64_t)1 << 30)

/* The JSON of a .gltf, or the JSON chunk of a .glb, within ENG_JSON_MAX_DEPTH and with nothing
 * after its value (eng_json_precheck), every accessor count an integer in 1..2^31-1 and every
 * sparse count one in 1..count (ENG_ERR_INVALID naming the accessor); *max_external (may be NULL) gets the largest size an
 * external file of this glTF may have: the largest buffer byteLength (+ 3 bytes of padding),
 * within SCN_EXTERNAL_MIN..SCN_EXTERNAL_MAX. */
eng_result scn_gltf_precheck(const char *path, const char *bytes, size_t len, uint64_t *max_external,
                             eng_error *err);

/* The size a PNG or JPEG header declares: 1 and w, h when found, 0 for other formats or a
 * header too short to say (the decoder then judges). */
int scn_image_header_size(const unsigned char *bytes, size_t len, uint32_t *w, uint32_t *h);

#ifdef __cplusplus
}
#endif

#endif
