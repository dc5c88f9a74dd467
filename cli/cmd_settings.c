/* cmd_settings.c — `ispm settings [--markdown]`: every key a sequence's "settings" object
 * takes, from engine/core/settings.def through eng_settings_table: key, type, default, range
 * or names, meaning. docs/settings.md is its --markdown output (tests/e2e_settings_doc.sh
 * checks that the two agree). */
#include "eng.h"

#include <getopt.h>
#include <stdio.h>
#include <string.h>

enum { EXIT_OK = 0, EXIT_INPUT = 2 };

static void settings_usage(FILE *f)
{
    fprintf(f, "usage: ispm settings [--markdown]\n"
               "\n"
               "Lists every key of a sequence's \"settings\" object: its type, default, range or\n"
               "names, and meaning.\n"
               "\n"
               "  -m, --markdown     a Markdown table (docs/settings.md)\n"
               "  -h, --help         this text\n"
               "\n"
               "exit: 0; 2 bad arguments\n");
}

/* The default as a sequence would spell it. */
static void default_text(const eng_setting *d, char *out, size_t size)
{
    eng_settings s;
    memset(&s, 0, sizeof s);
    eng_settings_defaults(&s);
    eng_setting_format(d, &s, out, size);
}

/* The values a sequence may give, in the parser's words. */
static void range_text(const eng_setting *d, int markdown, char *out, size_t size)
{
    const char *q = markdown ? "`" : "\"";
    size_t at = 0;
    out[0] = 0;
    switch (d->type) {
    case ENG_SETTING_INT:
        at = (size_t)snprintf(out, size, "%.0f..%.0f", d->lo, d->hi);
        if (d->step > 1 && at < size)
            snprintf(out + at, size - at, ", %s", d->step_text);
        break;
    case ENG_SETTING_FLOAT:
        switch (d->ends) {
        case ENG_ENDS_CLOSED: snprintf(out, size, "%g..%g", d->lo, d->hi); break;
        case ENG_ENDS_OPEN_LO:
        case ENG_ENDS_POSITIVE: snprintf(out, size, "(%g, %g]", d->lo, d->hi); break;
        case ENG_ENDS_OPEN: snprintf(out, size, "(%g, %g)", d->lo, d->hi); break;
        }
        break;
    case ENG_SETTING_BOOL: snprintf(out, size, "true, false"); break;
    case ENG_SETTING_ENUM:
    case ENG_SETTING_NAME:
        for (int i = 0; i < d->name_count && at < size; i++)
            at += (size_t)snprintf(out + at, size - at, "%s%s%s%s", i ? ", " : "", q, d->names[i].name, q);
        break;
    }
    at = strlen(out);
    if (at < size)
        snprintf(out + at, size - at, "%s", d->note);
    at = strlen(out);
    if (d->word && at < size)
        snprintf(out + at, size - at, markdown ? ", or `\"%s\"`" : ", or \"%s\"", d->word);
}

int cmd_settings(int argc, char **argv)
{
    static const struct option opts[] = {{"markdown", no_argument, 0, 'm'}, {"help", no_argument, 0, 'h'}, {0, 0, 0, 0}};
    int markdown = 0, c;
    while ((c = getopt_long(argc, argv, "mh", opts, NULL)) != -1) {
        switch (c) {
        case 'm': markdown = 1; break;
        case 'h': settings_usage(stdout); return EXIT_OK;
        default: settings_usage(stderr); return EXIT_INPUT;
        }
    }
    if (optind != argc) {
        settings_usage(stderr);
        return EXIT_INPUT;
    }
    int count = 0;
    const eng_setting *table = eng_settings_table(&count);
    if (markdown) {
        printf("| key | type | default | range or names | meaning |\n");
        printf("|---|---|---|---|---|\n");
    }
    for (int i = 0; i < count; i++) {
        const eng_setting *d = &table[i];
        char def[64], range[400];
        default_text(d, def, sizeof def);
        range_text(d, markdown, range, sizeof range);
        if (markdown)
            printf("| `%s` | %s | `%s` | %s | %s |\n", d->key, d->type_name, def, range, d->meaning);
        else
            printf("%-20s %-5s %-13s %s\n%20s %s\n", d->key, d->type_name, def, range, "", d->meaning);
    }
    return EXIT_OK;
}
