/* tool_record.c — `ispm record` without replay: sequence + scene + engine + capture, nothing
 * else, for tests/memcheck.sh. The ispm binary also links replay, whose OpenImageIO pulls in
 * libhwy, whose load-time timer calibration uses RDTSCP; where a virtual CPU hides RDTSCP from
 * cpuid (as some sandboxes do), valgrind cannot decode it and no program linking OpenImageIO
 * starts under valgrind. This tool runs the whole recording path under memcheck anyway.
 * usage: ispm_test_record SEQUENCE RUN   (exit 0 ok, 1 failed, 2 bad input) */
#include "cap.h"
#include "eng.h"

#include <stdio.h>
#include <stdlib.h>

int main(int argc, char **argv)
{
    if (argc != 3) {
        fprintf(stderr, "usage: ispm_test_record SEQUENCE RUN\n");
        return 2;
    }
    eng_error err = {{0}};
    seq_sequence *seq = calloc(1, sizeof *seq);
    scn_scene *scene = NULL;
    eng_engine *eng = NULL;
    cap_capture *cap = NULL;
    int rc = 0;
    if (!seq)
        return 1;
    if (seq_load(argv[1], seq, &err) != ENG_OK || seq_load_scene(seq, &scene, &err) != ENG_OK) {
        fprintf(stderr, "ispm_test_record: %s\n", err.msg);
        free(seq);
        return 2;
    }
    eng_desc ed = {.scene = scene, .sequence = seq};
    cap_desc cd = {.run_dir = argv[2], .sequence = seq, .scene = scene, .tool_version = "test",
                   .git_revision = "test", .overwrite = 1, .determinism = eng_determinism_info()};
    if (eng_create(&ed, &eng, &err) != ENG_OK || cap_create(&cd, &cap, &err) != ENG_OK) {
        rc = 1;
    } else {
        eng_listener l = cap_listener(cap);
        eng_add_listener(eng, &l);
        for (int i = 0; i < seq->frame_count && rc == 0; i++)
            if (eng_render_frame(eng, i, &err) != ENG_OK)
                rc = 1;
        if (rc == 0 && cap_finish(cap, &err) != ENG_OK)
            rc = 1;
    }
    if (rc)
        fprintf(stderr, "ispm_test_record: %s\n", err.msg);
    cap_destroy(cap);
    eng_destroy(eng);
    scn_destroy(scene);
    free(seq);
    return rc;
}
