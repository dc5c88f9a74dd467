/* settings.c — settings.def at run time: one eng_setting per line (accessors, names, range),
 * the defaults and the enums' names, all expanded from the table so that a setting is spelled
 * once. The sequence parser, the manifest writer, the bench and `ispm settings` read the
 * table through eng_settings_table; none of them names a key. */
#include "eng_core.h"

#include <stdio.h>
#include <string.h>

#define ISPM_CLOSED ENG_ENDS_CLOSED
#define ISPM_OPEN_LO ENG_ENDS_OPEN_LO
#define ISPM_OPEN ENG_ENDS_OPEN
#define ISPM_POSITIVE ENG_ENDS_POSITIVE

/* Accessors and the manifest predicate of each line. */
#define NUMERIC_ACCESS(key, field, ctype)                                                                              \
    static double get_##key(const eng_settings *s) { return (double)s->field; }                                        \
    static void set_##key(eng_settings *s, double v) { s->field = (ctype)v; }
#define RECORDED(key, record)                                                                                          \
    static int recorded_##key(const eng_settings *s)                                                                   \
    {                                                                                                                  \
        (void)s;                                                                                                       \
        return (record) != 0;                                                                                          \
    }
#define ISPM_INT(key, field, def, lo, hi, step, not, record, meaning) NUMERIC_ACCESS(key, field, int) RECORDED(key, record)
#define ISPM_FLOAT(key, field, def, lo, hi, ends, exact, note, record, meaning)                                        \
    NUMERIC_ACCESS(key, field, float) RECORDED(key, record)
#define ISPM_FLOATWORD(key, field, def, lo, hi, ends, exact, note, record, meaning, word, flag)                     \
    NUMERIC_ACCESS(key, field, float) RECORDED(key, record)                                                            \
    static int word_get_##key(const eng_settings *s) { return s->flag; }                                               \
    static void word_set_##key(eng_settings *s, int on) { s->flag = on; }
#define ISPM_BOOL(key, field, def, record, meaning) NUMERIC_ACCESS(key, field, int) RECORDED(key, record)
/* An enum field is set through its own type (__typeof__-free: the value converts on assignment). */
#define ISPM_ENUM(key, field, def, note, record, meaning)                                                              \
    static double get_##key(const eng_settings *s) { return (double)s->field; }                                        \
    static void set_##key(eng_settings *s, double v) { s->field = (int)v; }                                            \
    RECORDED(key, record)                                                                                              \
    static const eng_setting_name NAMES_##key[] = {ISPM_NAMES_##key(NAME_ENTRY)};
#define ISPM_NAME(key, field, def, note, record, meaning)                                                              \
    static char *text_##key(eng_settings *s, size_t *size)                                                             \
    {                                                                                                                  \
        *size = sizeof s->field;                                                                                       \
        return s->field;                                                                                               \
    }                                                                                                                  \
    RECORDED(key, record)                                                                                              \
    static const eng_setting_name NAMES_##key[] = {ISPM_NAMES_##key(NAME_ENTRY)};
#define NAME_ENTRY(name, value) {name, value},
#include "settings.def"
#undef ISPM_INT
#undef ISPM_FLOAT
#undef ISPM_FLOATWORD
#undef ISPM_BOOL
#undef ISPM_ENUM
#undef ISPM_NAME

#define COUNT(a) ((int)(sizeof a / sizeof a[0]))
static const eng_setting TABLE[] = {
#define ISPM_INT(k_, field, def_, lo_, hi_, step_, not, record, meaning_)                                             \
    {.key = #k_, .type = ENG_SETTING_INT, .type_name = "int", .def = (def_), .lo = (lo_), .hi = (hi_),              \
     .step = (step_), .step_text = (not), .note = "", .meaning = (meaning_), .get = get_##k_, .set = set_##k_,     \
     .recorded = recorded_##k_},
#define ISPM_FLOAT(k_, field, def_, lo_, hi_, ends_, exact_, note_, record, meaning_)                                 \
    {.key = #k_, .type = ENG_SETTING_FLOAT, .type_name = "float", .def = (def_), .lo = (lo_), .hi = (hi_),          \
     .ends = (ends_), .exact = (exact_), .note = (note_), .meaning = (meaning_), .get = get_##k_,                    \
     .set = set_##k_, .recorded = recorded_##k_},
#define ISPM_FLOATWORD(k_, field, def_, lo_, hi_, ends_, exact_, note_, record, meaning_, word_, flag)             \
    {.key = #k_, .type = ENG_SETTING_FLOAT, .type_name = "float", .def = (def_), .lo = (lo_), .hi = (hi_),          \
     .ends = (ends_), .exact = (exact_), .note = (note_), .meaning = (meaning_), .get = get_##k_,                    \
     .set = set_##k_, .recorded = recorded_##k_, .word = (word_), .word_get = word_get_##k_,                        \
     .word_set = word_set_##k_},
#define ISPM_BOOL(k_, field, def_, record, meaning_)                                                                  \
    {.key = #k_, .type = ENG_SETTING_BOOL, .type_name = "bool", .def = (def_), .lo = 0, .hi = 1, .note = "",        \
     .meaning = (meaning_), .get = get_##k_, .set = set_##k_, .recorded = recorded_##k_},
#define ISPM_ENUM(k_, field, def_, note_, record, meaning_)                                                           \
    {.key = #k_, .type = ENG_SETTING_ENUM, .type_name = "enum", .def = (def_), .names = NAMES_##k_,               \
     .name_count = COUNT(NAMES_##k_), .note = (note_), .meaning = (meaning_), .get = get_##k_, .set = set_##k_,   \
     .recorded = recorded_##k_},
#define ISPM_NAME(k_, field, def_, note_, record, meaning_)                                                           \
    {.key = #k_, .type = ENG_SETTING_NAME, .type_name = "name", .def_name = (def_), .names = NAMES_##k_,          \
     .name_count = COUNT(NAMES_##k_), .note = (note_), .meaning = (meaning_), .text = text_##k_,                   \
     .recorded = recorded_##k_},
#include "settings.def"
#undef ISPM_INT
#undef ISPM_FLOAT
#undef ISPM_FLOATWORD
#undef ISPM_BOOL
#undef ISPM_ENUM
#undef ISPM_NAME
};

const eng_setting *eng_settings_table(int *count)
{
    *count = COUNT(TABLE);
    return TABLE;
}

const eng_setting *eng_setting_find(const char *key)
{
    for (int i = 0; key && i < COUNT(TABLE); i++)
        if (strcmp(TABLE[i].key, key) == 0)
            return &TABLE[i];
    return NULL;
}

const char *eng_setting_value_name(const eng_setting *d, int value)
{
    if (d->type == ENG_SETTING_ENUM && value == 0)
        value = (int)d->def;
    for (int i = 0; i < d->name_count; i++)
        if (d->names[i].value == value)
            return d->names[i].name;
    return "unknown";
}

void eng_setting_format(const eng_setting *d, const eng_settings *s, char *out, size_t size)
{
    switch (d->type) {
    case ENG_SETTING_INT: snprintf(out, size, "%d", (int)d->get(s)); break;
    case ENG_SETTING_FLOAT:
        if (d->word && d->word_get(s))
            snprintf(out, size, "%s", d->word);
        else
            snprintf(out, size, "%g", d->get(s));
        break;
    case ENG_SETTING_BOOL: snprintf(out, size, "%s", d->get(s) != 0.0 ? "true" : "false"); break;
    case ENG_SETTING_ENUM: snprintf(out, size, "%s", eng_setting_value_name(d, (int)d->get(s))); break;
    case ENG_SETTING_NAME: {
        size_t n = 0;
        const char *t = d->text((eng_settings *)s, &n);
        snprintf(out, size, "%.*s", (int)n, t); /* stops at the NUL, or at the field's end */
        break;
    }
    }
}

void eng_settings_defaults(eng_settings *s)
{
    for (int i = 0; i < COUNT(TABLE); i++) {
        const eng_setting *d = &TABLE[i];
        if (d->type == ENG_SETTING_NAME) {
            size_t n = 0;
            char *t = d->text(s, &n);
            if (!t[0])
                snprintf(t, n, "%s", d->def_name);
        } else if (d->get(s) == 0.0) {
            d->set(s, d->def);
        }
    }
}

/* The enums' names, for the engine's own use (method lookups by name, logs). */
#define ENUM_NAME(fn, type, key)                                                                                       \
    const char *fn(type m) { return eng_setting_value_name(&TABLE[SETTING_##key], (int)m); }
enum {
#define ISPM_INT(key, ...) SETTING_##key,
#define ISPM_FLOAT(key, ...) SETTING_##key,
#define ISPM_FLOATWORD(key, ...) SETTING_##key,
#define ISPM_BOOL(key, ...) SETTING_##key,
#define ISPM_ENUM(key, ...) SETTING_##key,
#define ISPM_NAME(key, ...) SETTING_##key,
#include "settings.def"
#undef ISPM_INT
#undef ISPM_FLOAT
#undef ISPM_FLOATWORD
#undef ISPM_BOOL
#undef ISPM_ENUM
#undef ISPM_NAME
};
ENUM_NAME(eng_indirect_name, eng_indirect, indirect)
ENUM_NAME(eng_trace_name, eng_photon_trace, photon_trace)
ENUM_NAME(eng_miss_name, eng_miss_mode, multi_image_miss)
ENUM_NAME(eng_specular_name, eng_specular, specular)
ENUM_NAME(eng_scaling_name, eng_kernel_scaling, kernel_scaling)
ENUM_NAME(eng_random_name, eng_random_mode, random)
ENUM_NAME(eng_detail_name, eng_atrous_detail, atrous_detail)
ENUM_NAME(eng_boundary_name, eng_boundary, boundary)
ENUM_NAME(eng_pcss_blocker_name, eng_pcss_blocker, pcss_blocker)
