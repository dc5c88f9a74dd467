/* replay_internal.h — what replay.c offers bless.c and the tests beyond rep.h: the replay walk
 * with its report model handed back, for a caller that reads the entries itself.
 */
#ifndef ISPM_REPLAY_INTERNAL_H
#define ISPM_REPLAY_INTERNAL_H

#include "eng_core.h"
#include "rep.h"
#include "rep_report.h"
#include "rep_run.h"

/* rep_replay without the summary: fills r (free with rep_report_free) and writes the report
 * files; returns r->exit. */
rep_exit rep_replay_report(const rep_options *o, rep_report *r, eng_error *err);

/* Creates the parent folders of path (path names a file or folder). */
eng_result rep_make_parent(const char *path, eng_error *err);

/* golden_store.c: moves the finished tmp folder into golden's place (the old golden aside, then
 * removed), so a reader sees the old golden or the new one. */
eng_result rep_swap_in(const char *golden, const char *tmp, eng_error *err);
/* A bless or migrate ended between rep_swap_in's two renames leaves <golden>.old and no
 * <golden>: the old golden is renamed back (the new one was never reviewed into place). A
 * <golden>.old beside a golden is the remains of a finished swap (its renderer sets kept), and a
 * <golden>.tmp those of a command that ended before its swap: both are removed. Called under the
 * golden's lock. */
eng_result rep_golden_recover(const char *golden, eng_error *err);

/* ---------------------------------------------------------------- golden_store.c */

typedef struct rep_store_stats {
    size_t buffers;      /* buffers put */
    int objects_new;     /* objects written */
    int objects_had;     /* objects the store held already (read back and checked) */
    uint64_t bytes_new;  /* bytes of the objects written */
} rep_store_stats;

/* The shared store for a golden at path golden: the first of ../objects, ../../objects,
 * ../../../objects that is a folder (not a link). Returns its path and sets *rel to the relative
 * name for the manifest (caller frees both); NULL when there is none. */
char *rep_store_find(const char *golden, char **rel);
/* Stores part p (buffer b, already verified against b's digest) as an object unless the store
 * holds it; either way the object is read back and checked. */
eng_result rep_store_put(const char *store, const rep_buffer_info *b, const rep_part *p, rep_store_stats *st,
                         eng_error *err);
/* Every buffer of every frame of run (decoded and verified) put into store. */
eng_result rep_store_put_run(const rep_run *run, const char *store, rep_store_stats *st, eng_error *err);
/* The run's manifest as a golden's at dst: "capture": {"compression": "zip"}; with objects_rel,
 * format_version 2, "objects": objects_rel and no frame "file". Nothing else changes. */
eng_result rep_store_write_manifest(const rep_run *run, const char *dst, const char *objects_rel, eng_error *err);

#endif
