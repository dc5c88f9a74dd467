/* merge.h — frame shards merged into one run (ispm merge).
 *
 * A shard (ispm record --frames A-B --warmup W --overlap O, cap_desc.shard) is a complete run
 * of frames A-O..B of a sequence whose temporal state was rebuilt from frame A-W. cap_merge
 * proves, from the shards' manifests alone, that their frames are the frames one machine would
 * have recorded, then writes them as one run:
 *   1. every shard is complete (manifest.json) and a shard, and all were recorded from the
 *      same sequence, scene, settings, GL, pinned determinism settings and binary (the
 *      manifest's provenance: tool version and git revision);
 *   2. their ranges A-B cover 0..frame_count-1 without a gap or a frame twice;
 *   3. each shard but the first wrote O >= 1 overlap frames before A, and every buffer digest
 *      of those frames equals that of the shard that owns the frame: the warm-up reproduced
 *      the temporal state bit for bit, so every later frame is the same too. Otherwise merge
 *      refuses with one line naming the frame, the buffer and the warm-up the state needs (the
 *      owner's "history_from": how far back the state of frame A-1 reaches).
 * The merged run is written like a recording: run.json, then each frame's EXR (hard-linked,
 * or copied, from its shard) and record atomically, and manifest.json last, so a merge killed
 * at any moment leaves no complete-looking run. Its manifest is the first shard's with every
 * frame, frame_count and "command" of a whole run, plus "shards" (each shard's folder, range,
 * warm-up, overlap and command): it differs from a one-machine recording's only in timing and
 * that provenance. */
#ifndef ISPM_CAP_MERGE_H
#define ISPM_CAP_MERGE_H

#include "seq.h"

#ifdef __cplusplus
extern "C" {
#endif

/* "A-B" or "A": frame indices 0 <= A <= B <= 10^7, decimal digits only. 1 and the range on
 * success, 0 otherwise (nothing written). */
int cap_parse_range(const char *s, int *first, int *last);

/* Are shards first[i]..last[i] (i < count, sorted by first) exactly 0..frame_count-1? names[i]
 * names shard i in the message. ENG_OK, or ENG_ERR_INVALID with one line naming the frames
 * missing (a gap, the start, the end) or held twice and the shards. */
eng_result cap_merge_coverage(const int *first, const int *last, const char *const *names, int count,
                              int frame_count, eng_error *err);

typedef struct cap_merge_desc {
    const char *const *shards; /* shard run folders, any order */
    int shard_count;           /* >= 1 */
    const char *run_dir;       /* the merged run to create */
    int overwrite;             /* replace a run already in run_dir (as record --force) */
    const char *command_line;  /* recorded as "command"; may be NULL */
} cap_merge_desc;

/* Checks and merges (above). ENG_OK: run_dir is a complete run. ENG_ERR_INVALID: the shards
 * cannot be merged (incomplete, not shards, other provenance, gaps, an overlap that differs,
 * no overlap): nothing is written. ENG_ERR_IO: a shard is unreadable or writing failed
 * (run_dir then has no manifest). err gets one line. */
eng_result cap_merge(const cap_merge_desc *desc, eng_error *err);

#ifdef __cplusplus
}
#endif

#endif
