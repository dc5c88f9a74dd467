/* fuzz_sequence.c — libFuzzer target for the sequence parser (seq_parse, engine/scene/sequence.c).
 *
 * Each input is parsed as the bytes of "/nonexistent/fuzz.json"; the parser only resolves the
 * scene path, it never opens it, so the target reads no file. On every input the contract is
 * checked: a failure leaves a one-line non-empty message; a success satisfies the invariants
 * eng.h promises (frame_count >= 1, fps > 0 and finite, width and height in 1..16384, camera
 * keys and capture patterns within their arrays, a camera by node name, node index or keys), and seq_wants is exercised on a few buffer
 * names so the stored glob patterns are known to be NUL-terminated and usable. */
#define _POSIX_C_SOURCE 200809L
#include "seq.h"

#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    static seq_sequence seq; /* ~40 KB: static rather than on the stack */
    memset(&seq, 0, sizeof seq);
    eng_error err = {{0}};
    eng_result r = seq_parse("/nonexistent/fuzz.json", (const char *)data, size, &seq, &err);
    if (r != ENG_OK) {
        size_t n = strnlen(err.msg, sizeof err.msg);
        if (n == 0 || n == sizeof err.msg || memchr(err.msg, '\n', n))
            abort();
        return 0;
    }
    if (seq.frame_count < 1 || !(seq.fps > 0) || !isfinite(seq.fps) || seq.width < 1 || seq.width > 16384 ||
        seq.height < 1 || seq.height > 16384 || seq.capture_count < 0 || seq.capture_count > SEQ_MAX_CAPTURE ||
        seq.camera_key_count < 0 || seq.camera_key_count > SEQ_MAX_CAMKEYS ||
        (!seq.camera_node[0] && !seq.camera_by_index && !seq.camera_frame && seq.camera_key_count < 1) ||
        (seq.camera_frame && !(fabsf(seq.camera_direction[0]) + fabsf(seq.camera_direction[1]) +
                                   fabsf(seq.camera_direction[2]) > 0.0f)) ||
        (seq.camera_by_index && seq.camera_node_index < 0))
        abort();
    static const char *const names[] = {"gbuffer.depth", "shadow.light0.face3", "final.display", ""};
    for (size_t i = 0; i < sizeof names / sizeof names[0]; i++)
        (void)seq_wants(&seq, names[i]);
    return 0;
}
