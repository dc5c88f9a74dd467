/* glsl_sources.h — lookup of the GLSL files under engine/gl/shaders/, embedded at build time by
 * cmake/embed_glsl.cmake. */
#ifndef ISPM_GLSL_SOURCES_H
#define ISPM_GLSL_SOURCES_H
/* The text of shaders/<name> (e.g. "gbuffer.vert.glsl"), or NULL if there is no such file. */
const char *eng_glsl_source(const char *name);
#endif
