// Progressive photon mapping's per-pixel radius (engine/progressive.h, "progressive_radius":
// "pixel"), for the photon programs compiled with PIXEL_SCALE (ind_scatter_splat.c, ind_quads.c):
// KERNEL_RADIUS is the photon's (r_xy, r_z) times this pixel's scale (≤ 1, so what the photon
// draws still covers every pixel its kernel reaches); without PIXEL_SCALE it is v_radius itself.
// Expects v_radius and, where KERNEL_RADIUS is used, the pixel px.
#ifdef PIXEL_SCALE
uniform sampler2D u_pixel_scale;
#define KERNEL_RADIUS (v_radius * texelFetch(u_pixel_scale, px, 0).x)
#else
#define KERNEL_RADIUS v_radius
#endif
