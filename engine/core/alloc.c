/* alloc.c — allocation that cannot fail: every engine room allocates through eng_xmalloc and
 * eng_xcalloc, and runs out of memory through the one hook, eng_oom, which names what could
 * not be had and ends the process (a renderer half-way through a frame has no state worth
 * keeping, and a run without its manifest is never mistaken for a complete one). */
#include "eng_core.h"

#include <stdio.h>
#include <stdlib.h>

void eng_oom(const char *what)
{
    fprintf(stderr, "ispm: out of memory%s%s\n", what ? ": " : "", what ? what : "");
    abort();
}

void *eng_xmalloc(size_t size)
{
    void *p = malloc(size ? size : 1);
    if (!p)
        eng_oom(NULL);
    return p;
}

void *eng_xcalloc(size_t n, size_t size)
{
    void *p = calloc(n ? n : 1, size);
    if (!p)
        eng_oom(NULL);
    return p;
}
