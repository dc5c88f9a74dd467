/* run_internal.h — what run.c and objects.c share inside the run room. */
#ifndef ISPM_REP_RUN_INTERNAL_H
#define ISPM_REP_RUN_INTERNAL_H

#include "rep_run.h"

/* The decoded part p (read from path) against the manifest's record b: size, channel set,
 * digest and non-finite counts. */
/* Does the decoded part (or a part header) have exactly the manifest's channel set, by name? */
int rep_run_same_channels(const rep_part *p, const rep_buffer_info *b);

eng_result rep_run_verify_part(const char *path, const rep_part *p, const rep_buffer_info *b, eng_error *err);

/* The object store that a format-2 manifest mf (in folder dir) names with rel: "objects", or
 * "../objects" up to three parents up; anything else escapes the golden (ENG_ERR_INVALID). The
 * store must be a folder, not a symbolic link. *store: dir joined with rel (caller frees). */
eng_result rep_objects_resolve(const char *dir, const char *mf, const char *rel, char **store, eng_error *err);

/* The cache of a format-2 golden's last decoded frame (objects.c): made by rep_run_open, freed
 * by rep_run_close (NULL accepted). */
struct rep_object_cache *rep_object_cache_create(void);
void rep_object_cache_free(struct rep_object_cache *c);

/* Every buffer of a format-2 frame read from the run's store, verified (objects.c). A buffer
 * whose digest the previous frame read also had (a static shadow map, the G-buffer of a still
 * camera) is copied from it rather than decoded again. */
eng_result rep_objects_read_frame(const rep_run *run, int frame, rep_part **out, eng_error *err);

#endif
