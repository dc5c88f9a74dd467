/* report_write.c — a replay's report as files: report.json and report.txt, then
 * report.junit.xml and report.html, each written atomically into the report folder so that a
 * reader never sees half a report, all from the same entries in the same worst-first order.
 */
#include "rep_report.h"
#include "rep_run.h"
#include "rep_util.h"

#include <stdlib.h>
#include <string.h>

/* The name CI shows for the run: the sequence's, else the run folder's last component. */
static char *suite_name(const rep_report *r, const rep_run *run, const rep_run *golden)
{
    if (run && run->sequence_name)
        return rep_xstrdup(run->sequence_name);
    if (golden && golden->sequence_name)
        return rep_xstrdup(golden->sequence_name);
    const char *d = r->run_dir ? r->run_dir : "run";
    size_t n = strlen(d);
    while (n > 1 && d[n - 1] == '/')
        n--;
    size_t a = n;
    while (a > 0 && d[a - 1] != '/')
        a--;
    return n > a ? rep_xprintf("%.*s", (int)(n - a), d + a) : rep_xstrdup("run");
}

eng_result rep_report_write(const rep_report *r, const char *dir, eng_error *err)
{
    eng_result res = rep_mkdirs(dir, err);
    if (res != ENG_OK)
        return res;
    char *json = rep_report_json(r);
    char *txt = rep_report_text(r, 0);
    char *jp = rep_path_join(dir, "report.json");
    char *tp = rep_path_join(dir, "report.txt");
    res = rep_write_atomic(jp, json, strlen(json), err);
    if (res == ENG_OK)
        res = rep_write_atomic(tp, txt, strlen(txt), err);
    free(jp);
    free(tp);
    free(json);
    free(txt);
    if (res != ENG_OK)
        return res;

    /* The JUnit and HTML writers want the manifests again (sequence name, frame files for the
     * thumbnails); an input that cannot be opened only costs them those. */
    rep_run *run = NULL, *golden = NULL;
    eng_error ignored;
    if (r->run_dir && rep_run_open(r->run_dir, &run, &ignored) != ENG_OK)
        run = NULL;
    if (r->golden_dir && rep_run_open(r->golden_dir, &golden, &ignored) != ENG_OK)
        golden = NULL;
    char *suite = suite_name(r, run, golden);
    char *xml = rep_report_junit(r, suite);
    char *xp = rep_path_join(dir, "report.junit.xml");
    res = rep_write_atomic(xp, xml, strlen(xml), err);
    if (res == ENG_OK)
        res = rep_report_html_write(r, run, golden, dir, err);
    free(xp);
    free(xml);
    free(suite);
    rep_run_close(golden);
    rep_run_close(run);
    return res;
}
