/* fuzz_gltf.c — libFuzzer target for the glTF loader (tinygltf shim + gltf_load.c validation).
 *
 * Each input is handed to scn_load_gltf_memory as the bytes of a file named
 * "/nonexistent/fuzz.gltf" (or .glb when it starts with the GLB magic; the shim decides by the
 * magic, not the name), so external-buffer URIs resolve to nothing and the loader must report
 * an I/O error rather than read the host's files. The loader's contract is checked on every
 * input: it returns a result code, on failure *out is NULL and the message is one non-empty
 * line; on success the scene it returns is consistent enough to evaluate at a few times
 * (world matrices of every node), which walks the node order and the animation channels.
 * Sanitizers (ASan, UBSan) turn any memory or undefined-behaviour error into a finding. */
#define _POSIX_C_SOURCE 200809L
#include "scn.h"

#include <stdint.h>
#include <stdlib.h>
#include <string.h>

/* Aborts (a libFuzzer finding) when the loader breaks its error contract. */
static void check_message(const eng_error *err)
{
    size_t n = strnlen(err->msg, sizeof err->msg);
    if (n == 0 || n == sizeof err->msg || memchr(err->msg, '\n', n))
        abort();
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    scn_scene *scene = NULL;
    eng_error err = {{0}};
    eng_result r = scn_load_gltf_memory("/nonexistent/fuzz.gltf", data, size, &scene, &err);
    if (r != ENG_OK) {
        if (scene)
            abort();
        check_message(&err);
        return 0;
    }
    if (!scene)
        abort();
    if (scene->node_count <= 4096) {
        float *world = malloc((scene->node_count ? scene->node_count : 1) * 16 * sizeof *world);
        if (world) {
            static const double times[] = {-1.0, 0.0, 0.37, 1.0, 1e6};
            for (size_t i = 0; i < sizeof times / sizeof times[0]; i++)
                scn_evaluate(scene, times[i], world);
            free(world);
        }
    }
    scn_destroy(scene);
    return 0;
}
