/* renderer.c — which GL renderer made the run and which the golden (the manifests'
 * gl.renderer, GL_RENDERER: "llvmpipe (LLVM 15.0.6, 128 bits)", a GPU's name). Goldens are
 * blessed per renderer: OSMesa's and Mesa's EGL llvmpipe are the same renderer and
 * bit-identical, so a run from either is held to the golden's own tolerances; a run from
 * another renderer (a GPU through EGL) cannot be, and is compared under the golden's
 * cross-renderer set (tolerance.c: "cross_renderer", or the built-in one) with "different
 * renderer" in the report. */
#define _POSIX_C_SOURCE 200809L

#include "rep_compare.h"
#include "rep_report.h"
#include "rep_run.h"
#include "rep_util.h"

#include <string.h>

const rep_tolerances *rep_renderer_tolerances(rep_report *r, const rep_run *run, const rep_run *gold,
                                              const rep_tolerances *tols)
{
    r->run_renderer = run->gl_renderer ? rep_xstrdup(run->gl_renderer) : NULL;
    r->golden_renderer = gold->gl_renderer ? rep_xstrdup(gold->gl_renderer) : NULL;
    r->renderer_differs = run->gl_renderer && gold->gl_renderer && strcmp(run->gl_renderer, gold->gl_renderer) != 0;
    return r->renderer_differs && tols->cross ? tols->cross : tols;
}

char *rep_renderer_note(const rep_report *r)
{
    if (!r->renderer_differs)
        return NULL;
    return rep_xprintf("different renderer: run \"%s\", golden \"%s\": compared under the cross-renderer tolerances",
                       r->run_renderer, r->golden_renderer);
}
