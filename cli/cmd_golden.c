/* cmd_golden.c — `ispm golden`: keeping the store of a folder of goldens whose buffers are stored
 * once (replay/golden_store.c):
 *   `ispm golden migrate GOLDEN...`: goldens of frame files become goldens of objects, each checked
 *   buffer by buffer (digest and float bits) before it replaces the old one;
 *   `ispm golden gc ROOT [--dry-run]`: objects in ROOT/objects that no golden under ROOT lists
 *   are removed;
 *   `ispm golden unpack GOLDEN DIR`: a golden written again with frame files, for tools that read
 *   those. */
#define _POSIX_C_SOURCE 200809L
#include "rep.h"

#include <getopt.h>
#include <stdio.h>
#include <string.h>

enum { GOLD_OK = 0, GOLD_INPUT = 2, GOLD_WRITE = 3, GOLD_UNREADABLE = 4 };

static void golden_usage(FILE *f)
{
    fprintf(f, "usage: ispm golden migrate GOLDEN...\n"
               "       ispm golden gc ROOT [--dry-run]\n"
               "       ispm golden unpack GOLDEN DIR\n"
               "\n"
               "migrate: a golden of frame files (format 1) becomes a golden whose buffers are stored\n"
               "once, by digest, in the object store of its folder (GOLDEN/../objects, made if missing;\n"
               "format 2). Every buffer is verified on reading, the new golden is read back and must\n"
               "equal the old one buffer by buffer (name, digest, size, channels, float bits) before it\n"
               "replaces it. A golden already of format 2 is left as it is.\n"
               "gc: removes the objects of ROOT/objects that no golden under ROOT (renderer sets\n"
               "included) lists; any golden under ROOT that cannot be read stops it before anything is\n"
               "removed. --dry-run counts only.\n"
               "unpack: GOLDEN written again as a golden of frame files (DIR/frames/NNNNNN.exr, one\n"
               "multi-part EXR per frame, format 1) in the new folder DIR, for oiiotool, idiff and older\n"
               "builds (scripts/bisect.sh).\n"
               "\n"
               "exit: 0 done; 2 bad arguments; 3 writing failed; 4 an unreadable golden, object or store\n");
}

static int exit_of(eng_result r)
{
    switch (r) {
    case ENG_OK: return GOLD_OK;
    case ENG_ERR_IO:
    case ENG_ERR_NOMEM: return GOLD_WRITE;
    default: return GOLD_UNREADABLE;
    }
}

static int cmd_migrate(int argc, char **argv)
{
    if (argc < 1) {
        golden_usage(stderr);
        return GOLD_INPUT;
    }
    for (int i = 0; i < argc; i++) {
        eng_error err = {{0}};
        eng_result r = rep_golden_migrate(argv[i], stdout, &err);
        if (r != ENG_OK) {
            fprintf(stderr, "ispm golden migrate: %s\n", err.msg);
            /* an old golden that cannot be read is bad input; one that reads but cannot be
             * written or read back again is a writing failure */
            return exit_of(r);
        }
    }
    return GOLD_OK;
}

static int cmd_gc(int argc, char **argv)
{
    int dry = 0;
    const char *root = NULL;
    for (int i = 0; i < argc; i++) {
        if (!strcmp(argv[i], "--dry-run") || !strcmp(argv[i], "-n"))
            dry = 1;
        else if (argv[i][0] == '-' || root) {
            golden_usage(stderr);
            return GOLD_INPUT;
        } else
            root = argv[i];
    }
    if (!root) {
        golden_usage(stderr);
        return GOLD_INPUT;
    }
    rep_gc_stats st;
    eng_error err = {{0}};
    eng_result r = rep_golden_gc(root, dry, &st, &err);
    if (r != ENG_OK) {
        fprintf(stderr, "ispm golden gc: %s\n", err.msg);
        return r == ENG_ERR_IO && st.goldens ? GOLD_WRITE : GOLD_UNREADABLE;
    }
    printf("gc: %s: %d goldens, %zu objects listed (%llu bytes), %zu %s (%llu bytes)\n", root, st.goldens, st.kept,
           (unsigned long long)st.bytes_kept, st.removed, dry ? "unlisted, would be removed" : "unlisted removed",
           (unsigned long long)st.bytes_removed);
    return GOLD_OK;
}

int cmd_golden(int argc, char **argv)
{
    /* argv[0] is "golden" */
    if (argc < 2 || !strcmp(argv[1], "-h") || !strcmp(argv[1], "--help")) {
        golden_usage(argc < 2 ? stderr : stdout);
        return argc < 2 ? GOLD_INPUT : GOLD_OK;
    }
    if (!strcmp(argv[1], "migrate"))
        return cmd_migrate(argc - 2, argv + 2);
    if (!strcmp(argv[1], "unpack")) {
        if (argc != 4) {
            golden_usage(stderr);
            return GOLD_INPUT;
        }
        eng_error err = {{0}};
        eng_result r = rep_golden_unpack(argv[2], argv[3], stdout, &err);
        if (r != ENG_OK)
            fprintf(stderr, "ispm golden unpack: %s\n", err.msg);
        return exit_of(r);
    }
    if (!strcmp(argv[1], "gc"))
        return cmd_gc(argc - 2, argv + 2);
    fprintf(stderr, "ispm golden: unknown subcommand '%s' (migrate, gc, unpack)\n", argv[1]);
    return GOLD_INPUT;
}
