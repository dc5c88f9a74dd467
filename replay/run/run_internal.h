/* run_internal.h — what run.c and objects.c share inside the run room. */
#ifndef ISPM_REP_RUN_INTERNAL_H
#define ISPM_REP_RUN_INTERNAL_H

#include "rep_run.h"

/* The decoded part p (read from path) against the manifest's record b: size, channel set,
 * digest and non-finite counts. */
eng_result rep_run_verify_part(const char *path, const rep_part *p, const rep_buffer_info *b, eng_error *err);

/* The object store that a format-2 manifest mf (in folder dir) names with rel: "objects", or
 * "../objects" up to three parents up; anything else escapes the golden (ENG_ERR_INVALID). The
 * store must be a folder, not a symbolic link. *store: dir joined with rel (caller frees). */
eng_result rep_objects_resolve(const char *dir, const char *mf, const char *rel, char **store, eng_error *err);

/* Every buffer of a format-2 frame read from the run's store, verified (objects.c). */
eng_result rep_objects_read_frame(const rep_run *run, int frame, rep_part **out, eng_error *err);

#endif
