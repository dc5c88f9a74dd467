/* gltf_features.h — internal to the scene room: what is refused by name from the glTF's JSON
 * alone, before tinygltf reads anything (gltf_features.c). */
#ifndef ISPM_GLTF_FEATURES_H
#define ISPM_GLTF_FEATURES_H

#include "eng_core.h"

#include <stddef.h>

/* Whether the loader reads extension `name` (fully or as docs/gltf.md describes). */
int gltf_extension_supported(const char *name);

/* Refuses, with one line naming the file and the feature (ENG_ERR_UNSUPPORTED): glTF 1.0 (a
 * GLB container of version 1, asset.version below 2, or 1.0's name-keyed objects), an
 * asset.version or asset.minVersion above 2.0, and any extensionsRequired entry the loader does
 * not read. Bytes that are not a glTF it can parse pass: tinygltf then names their problem.
 * *no_mesh gets 1 for a glTF (it has an asset) in which no node names a mesh or no mesh has a
 * primitive: it cannot draw anything, whatever else it holds. */
eng_result gltf_features_check(const char *path, const char *bytes, size_t len, int *no_mesh, eng_error *err);

#endif
