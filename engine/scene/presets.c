/* presets.c — the `"preset"` setting's bundles (docs/final-gather.md): each is a settings object
 * that the sequence parser applies, through the same checks as a sequence's own keys, before
 * those keys, so that any key the sequence gives overrides the preset's. Each bundle is a point
 * on the Pareto front of bench/final-gather.json's chart (Cornell box, 256×256, 32,768 photons,
 * against `ispm reference`):
 *
 *   draft        the tile gather (002 §6.3): the cheapest method with indirect light
 *   interactive  the final gather (003 App. A) at 1/4 resolution with joint bilateral
 *                upsampling (003 §5.2), directions seeded by the surface (003 §4.1), gathered
 *                light reused by reprojection, temporal accumulation (002 §7.2): the best
 *                one-frame accuracy at no more than half the k-d gather's time
 *   converged    the final gather at full resolution, stratified over frames (002 §4.2), its
 *                running mean while nothing moves */
#include "seq.h"

#include <stddef.h>

const char *seq_preset_settings(eng_preset p)
{
    switch (p) {
    case ENG_PRESET_DRAFT: return "{\"indirect\": \"tile-gather\"}";
    case ENG_PRESET_INTERACTIVE:
        return "{\"indirect\": \"final-gather\", \"final_gather_rays\": 64, \"final_gather_radius\": 0.15, "
               "\"final_gather_seed\": \"surface\", \"final_gather_reuse\": 16, \"splat_subsample\": 4, "
               "\"atrous_iterations\": 3, \"atrous_detail\": \"none\", "
               "\"temporal\": true}";
    case ENG_PRESET_CONVERGED:
        return "{\"indirect\": \"final-gather\", \"final_gather_rays\": 64, \"random\": \"stratified\", "
               "\"progressive\": true}";
    default: return NULL;
    }
}
