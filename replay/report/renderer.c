/* renderer.c — which GL renderer made the run and which the golden (the manifests'
 * gl.renderer, GL_RENDERER: "llvmpipe (LLVM 15.0.6, 128 bits)", a GPU's name). Goldens are
 * blessed per renderer: OSMesa's and Mesa's EGL llvmpipe are the same renderer and
 * bit-identical, so a run from either is held to the golden's own tolerances; a run from
 * another renderer (a GPU through EGL) cannot be, and is compared under the golden's
 * cross-renderer set (tolerance.c: "cross_renderer", or the built-in one) with "different
 * renderer" in the report. A golden may hold a set per renderer (golden/renderers/<slug of
 * GL vendor and renderer>/, blessed from that renderer's runs): a run whose renderer has a set is
 * compared with it under its own tolerances, and the reports name the set. */
#define _POSIX_C_SOURCE 200809L

#include "rep_compare.h"
#include "rep_report.h"
#include "rep_run.h"
#include "rep_util.h"

#include <stdlib.h>
#include <string.h>

const rep_tolerances *rep_renderer_tolerances(rep_report *r, const rep_run *run, const rep_run *gold,
                                              const rep_tolerances *tols)
{
    r->run_renderer = run->gl_renderer ? rep_xstrdup(run->gl_renderer) : NULL;
    r->golden_renderer = gold->gl_renderer ? rep_xstrdup(gold->gl_renderer) : NULL;
    r->renderer_differs = run->gl_renderer && gold->gl_renderer && strcmp(run->gl_renderer, gold->gl_renderer) != 0;
    return r->renderer_differs && tols->cross ? tols->cross : tols;
}

char *rep_renderer_set_dir(const char *golden_dir, const rep_run *run, const rep_run *gold, char **slug)
{
    *slug = NULL;
    if (!run->gl_renderer || !gold->gl_renderer)
        return NULL;
    char *mine = rep_renderer_slug(run->gl_vendor, run->gl_renderer);
    char *theirs = rep_renderer_slug(gold->gl_vendor, gold->gl_renderer);
    char *dir = NULL;
    if (strcmp(mine, theirs) != 0) {
        dir = rep_xprintf("%s/renderers/%s", golden_dir, mine);
        char *mf = rep_path_join(dir, "manifest.json");
        if (!rep_is_file(mf)) {
            free(dir);
            dir = NULL;
        }
        free(mf);
    }
    free(theirs);
    if (dir)
        *slug = mine;
    else
        free(mine);
    return dir;
}

char *rep_renderer_note(const rep_report *r)
{
    if (r->renderer_set)
        return rep_xprintf("renderer set %s: the golden's set for the run's renderer \"%s\"", r->renderer_set,
                           r->run_renderer ? r->run_renderer : "?");
    if (!r->renderer_differs)
        return NULL;
    return rep_xprintf("different renderer: run \"%s\", golden \"%s\": compared under the cross-renderer tolerances",
                       r->run_renderer, r->golden_renderer);
}
