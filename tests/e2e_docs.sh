#!/usr/bin/env bash
# The user documentation can be followed: README.md is short and shows the two commands; the
# CHANGELOG keeps an Unreleased section; the sequence example equals the CI sequence; no user doc
# names an issue or a session (and the scan catches one that does); docs/man/ispm.1 is what
# scripts/man_pages.py makes of today's --help, lists exactly the commands `ispm --help` lists and
# gives each command the exit codes its --help gives; ispm-view.1 documents every option of
# ispm-view --help; both man pages render without a warning;
# `cmake --install` installs the programs and the pages where man finds them; bench/record.sh
# writes a complete record; every relative link (and #anchor into a Markdown page) resolves.
# usage: e2e_docs.sh ISPM SOURCE_DIR WORK_DIR
set -u
ISPM=$1; SRC=$2; WORK=$3
BUILD=$(cd "$(dirname "$ISPM")/.." && pwd)
fail() { echo "FAIL: $*"; exit 1; }
skip() { echo "SKIP: $*"; [ "${ISPM_REQUIRE_DEPS:-0}" = 1 ] && exit 1; exit 77; }
rm -rf "$WORK"; mkdir -p "$WORK"
command -v man > /dev/null || skip "man (Debian: man-db) is not installed"

# README: at most 300 lines, both commands in a code block.
lines=$(wc -l < "$SRC/README.md")
[ "$lines" -le 300 ] || fail "README.md has $lines lines (at most 300)"
for cmd in scripts/demo.sh scripts/test.sh; do
  grep -qx "$cmd" "$SRC/README.md" || fail "README.md does not show the command $cmd on a line of its own"
done
grep -q '^## \[Unreleased\]' "$SRC/CHANGELOG.md" || fail "CHANGELOG.md has no '## [Unreleased]' section"

# The sequence example is the CI sequence, byte for byte.
sed -n '/^```json$/,/^```$/p' "$SRC/docs/sequences-and-scenes.md" | awk 'NR>1 && /^```$/ {exit} NR>1' > "$WORK/example.json"
cmp -s "$WORK/example.json" "$SRC/scenes/cornell-box/cornell-box-ci.json" ||
  { diff "$WORK/example.json" "$SRC/scenes/cornell-box/cornell-box-ci.json"; fail "the example in docs/sequences-and-scenes.md differs from cornell-box-ci.json"; }

# No issue or session numbers in the user docs; and the scan finds one that is there.
python3 "$SRC/scripts/house.py" --docs "$SRC" --check > "$WORK/history.txt" ||
  { cat "$WORK/history.txt"; fail "the user docs name issues or sessions (scripts/house.py --docs)"; }
mkdir -p "$WORK/tree/docs"
cp "$SRC/README.md" "$WORK/tree/"
printf '# A page\n\nMeasured in session 12.\n' > "$WORK/tree/docs/page.md"
python3 "$SRC/scripts/house.py" --docs "$WORK/tree" --check > "$WORK/injected.txt"
[ $? -eq 1 ] && grep -q 'docs/page.md:3' "$WORK/injected.txt" || { cat "$WORK/injected.txt"; fail "house.py --docs does not catch a session number"; }

# ispm.1: generated from today's --help, and its commands are ispm --help's.
python3 "$SRC/scripts/man_pages.py" "$ISPM" --check || fail "docs/man/ispm.1 is stale: run scripts/man_pages.py"
"$ISPM" --help | sed -n '/^commands:/,/^$/p' | sed -n 's/^  \([a-z][a-z-]*\).*/\1/p' > "$WORK/help_commands.txt"
python3 "$SRC/scripts/man_pages.py" --commands "$SRC/docs/man/ispm.1" > "$WORK/man_commands.txt"
[ "$(wc -l < "$WORK/help_commands.txt")" -ge 10 ] || fail "ispm --help lists too few commands"
diff "$WORK/help_commands.txt" "$WORK/man_commands.txt" || fail "the commands of ispm.1 differ from ispm --help's"
for cmd in $(cat "$WORK/help_commands.txt"); do
  grep -q "^\.SS $cmd\$" "$SRC/docs/man/ispm.1" || fail "ispm.1 has no options section for $cmd"
done
# Every command's EXIT STATUS entry gives the codes its --help gives.
python3 "$SRC/scripts/man_pages.py" --exit-codes "$ISPM" || fail "EXIT STATUS in docs/man/ispm.1.in and --help disagree"

# Both pages render, without a warning.
for page in ispm.1 ispm-view.1; do
  LC_ALL=C.UTF-8 MANWIDTH=80 man --warnings -E UTF-8 -l "$SRC/docs/man/$page" > "$WORK/$page.txt" 2> "$WORK/$page.err" ||
    fail "man -l docs/man/$page exited $?"
  [ ! -s "$WORK/$page.err" ] || { cat "$WORK/$page.err"; fail "man -l docs/man/$page warns"; }
  [ "$(wc -l < "$WORK/$page.txt")" -ge 40 ] || fail "docs/man/$page renders to too little text"
done
grep -q 'EXIT STATUS' "$WORK/ispm.1.txt" || fail "ispm.1 renders without EXIT STATUS"
# ispm-view(1) (hand-written) documents every option the viewer's --help lists.
if [ -x "$BUILD/viewer/ispm-view" ]; then
  "$BUILD/viewer/ispm-view" --help | grep -o -- '--[a-z][a-z-]*' | sort -u > "$WORK/view_options.txt"
  [ -s "$WORK/view_options.txt" ] || fail "ispm-view --help lists no options"
  for opt in $(cat "$WORK/view_options.txt"); do
    grep -qF -- "$opt" "$WORK/ispm-view.1.txt" || fail "ispm-view.1 does not document $opt"
  done
fi

# cmake --install: the programs, the module and the pages, where man finds them.
cmake --install "$BUILD" --prefix "$WORK/prefix" > "$WORK/install.txt" 2>&1 || { cat "$WORK/install.txt"; fail "cmake --install failed"; }
[ -x "$WORK/prefix/bin/ispm" ] || fail "cmake --install did not install bin/ispm"
ls "$WORK"/prefix/lib*/ispm/libispm_oiio.so > /dev/null 2>&1 || ls "$WORK"/prefix/lib/*/ispm/libispm_oiio.so > /dev/null 2>&1 ||
  fail "cmake --install did not install the OpenImageIO module"
for page in ispm.1 ispm-view.1; do
  cmp -s "$WORK/prefix/share/man/man1/$page" "$SRC/docs/man/$page" || fail "cmake --install did not install man1/$page"
done
if [ -x "$BUILD/viewer/ispm-view" ]; then
  [ -x "$WORK/prefix/bin/ispm-view" ] || fail "cmake --install did not install bin/ispm-view"
fi
[ "$(MANPATH="$WORK/prefix/share/man" man -w ispm 2>/dev/null)" = "$WORK/prefix/share/man/man1/ispm.1" ] ||
  fail "man -w ispm does not find the installed page"
"$WORK/prefix/bin/ispm" --help > /dev/null || fail "the installed ispm --help exited $?"

# bench/record.sh writes a record with the command, its status, the commit and the machine.
RECORD_DIR="$WORK/records" bash "$SRC/bench/record.sh" settings -- "$ISPM" settings > /dev/null || fail "bench/record.sh exited $?"
for field in '- command: `' '- exit status: 0' '- commit: ' '- CPU: ' '- load average'; do
  grep -qF -- "$field" "$WORK/records/settings.md" || fail "bench/record.sh's record lacks '$field'"
done
grep -q '^kernel_radius ' "$WORK/records/settings.md" || fail "bench/record.sh's record lacks the command's output"
RECORD_DIR="$WORK/records" bash "$SRC/bench/record.sh" fails -- false > /dev/null; [ $? -eq 1 ] || fail "bench/record.sh must exit with the command's status"
grep -q -- '- exit status: 1' "$WORK/records/fails.md" || fail "bench/record.sh does not record a failing status"

# Relative links resolve: files, and #anchors into Markdown pages (GitHub's heading ids).
python3 - "$SRC" > "$WORK/links.txt" <<'PY' || { cat "$WORK/links.txt"; fail "broken links in the user docs"; }
import os, re, sys
root = sys.argv[1]
pages = ["README.md", "CHANGELOG.md"]
for d, dirs, names in os.walk(os.path.join(root, "docs")):
    pages += [os.path.relpath(os.path.join(d, n), root) for n in names if n.endswith(".md")]
def anchors(path):
    ids, fence, seen = set(), False, {}
    for line in open(path, encoding="utf-8"):
        if line.startswith("```"):
            fence = not fence
        m = None if fence else re.match(r"^#{1,6} (.*)", line)
        if m:
            s = re.sub(r"[^\w\- ]", "", m.group(1).strip().lower()).replace(" ", "-")
            n = seen.get(s, 0); seen[s] = n + 1
            ids.add(s if n == 0 else "%s-%d" % (s, n))
    return ids
bad = checked = 0
for p in sorted(pages):
    text = re.sub(r"```.*?```", "", open(os.path.join(root, p), encoding="utf-8").read(), flags=re.S)
    for target in re.findall(r"\]\(([^)\s]+)\)", text):
        if re.match(r"^[a-z]+:", target):
            continue
        checked += 1
        path, _, frag = target.partition("#")
        full = os.path.normpath(os.path.join(root, os.path.dirname(p), path)) if path else os.path.join(root, p)
        if not os.path.exists(full):
            print("%s: %s: no such file" % (p, target)); bad += 1
        elif frag and full.endswith(".md") and frag not in anchors(full):
            print("%s: %s: no such heading" % (p, target)); bad += 1
print("%d pages, %d relative links, %d broken" % (len(pages), checked, bad))
sys.exit(1 if bad else 0)
PY
cat "$WORK/links.txt"
echo "ok"
