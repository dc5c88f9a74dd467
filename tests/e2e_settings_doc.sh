#!/usr/bin/env bash
# docs/settings.md is generated: its table must be what `ispm settings --markdown` prints from
# engine/core/settings.def today. On a difference, regenerate it with scripts/settings_doc.sh.
# usage: e2e_settings_doc.sh ISPM SOURCE_DIR WORK_DIR
set -u
ISPM=$1; SRC=$2; WORK=$3
fail() { echo "FAIL: $*"; exit 1; }
rm -rf "$WORK"; mkdir -p "$WORK"

"$ISPM" settings --markdown > "$WORK/table.md" || fail "ispm settings --markdown exited $?"
[ "$(grep -c '^| `' "$WORK/table.md")" -ge 30 ] || fail "ispm settings --markdown lists too few settings"
# The document is the intro up to the table, then the table to the end of the file.
sed -n '/^| key |/,$p' "$SRC/docs/settings.md" > "$WORK/doc_table.md"
diff -u "$WORK/doc_table.md" "$WORK/table.md" > "$WORK/diff.txt" ||
  { cat "$WORK/diff.txt"; fail "docs/settings.md differs from ispm settings --markdown (run scripts/settings_doc.sh)"; }
"$ISPM" settings > "$WORK/plain.txt" || fail "ispm settings exited $?"
grep -q '^kernel_radius ' "$WORK/plain.txt" || fail "ispm settings does not list kernel_radius"
"$ISPM" settings --bogus > /dev/null 2>&1; [ $? -eq 2 ] || fail "a bad option must exit 2"
echo "ok"
