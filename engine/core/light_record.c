/* light_record.c — reading the manifest's per-frame "lights" (eng_light_record: each light's
 * shadow views, written by capture) back, for capture's --resume and for ispm lineage, which
 * projects an eye pixel into the shadow map it was tested against. Part of ispm_core (no GL). */
#include "eng_core.h"

#include <cjson/cJSON.h>
#include <string.h>

static int floats(const cJSON *a, float *out, int n)
{
    if (!cJSON_IsArray(a) || cJSON_GetArraySize(a) != n)
        return 0;
    for (int i = 0; i < n; i++) {
        const cJSON *v = cJSON_GetArrayItem(a, i);
        if (!cJSON_IsNumber(v))
            return 0;
        out[i] = (float)v->valuedouble;
    }
    return 1;
}

eng_result eng_light_records_parse(const char *path, const void *json, int *count, eng_light_record *lights,
                                   eng_error *err)
{
    static const char *const types[] = {"point", "spot", "directional"};
    const cJSON *arr = json;
    *count = 0;
    memset(lights, 0, ENG_MAX_LIGHT_RECORDS * sizeof *lights);
    if (!arr)
        return ENG_OK;
    if (!cJSON_IsArray(arr) || cJSON_GetArraySize(arr) > ENG_MAX_LIGHT_RECORDS)
        return eng_fail(err, ENG_ERR_INVALID, "%s: \"lights\" is not an array of at most %d", path,
                        ENG_MAX_LIGHT_RECORDS);
    int n = 0;
    const cJSON *o;
    cJSON_ArrayForEach(o, arr) {
        eng_light_record *r = &lights[n];
        const cJSON *type = cJSON_GetObjectItemCaseSensitive(o, "type");
        const cJSON *texel = cJSON_GetObjectItemCaseSensitive(o, "texel");
        const cJSON *far = cJSON_GetObjectItemCaseSensitive(o, "far");
        const cJSON *vps = cJSON_GetObjectItemCaseSensitive(o, "view_proj");
        r->type = -1;
        for (int t = 0; cJSON_IsString(type) && t < 3; t++)
            if (strcmp(type->valuestring, types[t]) == 0)
                r->type = t;
        int faces = cJSON_IsArray(vps) ? cJSON_GetArraySize(vps) : 0;
        int ok = r->type >= 0 && cJSON_IsNumber(texel) && cJSON_IsNumber(far) && faces >= 1 && faces <= 6 &&
                 floats(cJSON_GetObjectItemCaseSensitive(o, "position"), r->position, 3) &&
                 floats(cJSON_GetObjectItemCaseSensitive(o, "direction"), r->direction, 3);
        for (int k = 0; ok && k < faces; k++)
            ok = floats(cJSON_GetArrayItem(vps, k), r->view_proj[k], 16);
        if (!ok)
            return eng_fail(err, ENG_ERR_INVALID,
                            "%s: lights[%d] is not {\"type\": point|spot|directional, \"position\": [3], "
                            "\"direction\": [3], \"texel\", \"far\", \"view_proj\": [1..6 × [16]]}",
                            path, n);
        r->faces = faces;
        r->texel = (float)texel->valuedouble;
        r->far_value = (float)far->valuedouble;
        n++;
    }
    *count = n;
    return ENG_OK;
}
