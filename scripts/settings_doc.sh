#!/usr/bin/env bash
# Writes docs/settings.md from `ispm settings --markdown` (tests/e2e_settings_doc.sh checks
# that the two agree). usage: scripts/settings_doc.sh [ISPM] (default build/cli/ispm)
set -eu
ISPM=${1:-build/cli/ispm}
cd "$(dirname "$0")/.."
{
  echo "# Sequence settings"
  echo
  echo "Every key of a sequence file's \`\"settings\"\` object, generated from"
  echo "\`engine/core/settings.def\` by \`scripts/settings_doc.sh\` (\`ispm settings --markdown\`); do not edit the table by hand."
  echo "An absent key takes its default; a value outside its range or names is refused with a message naming the key."
  echo
  "$ISPM" settings --markdown
} > docs/settings.md
