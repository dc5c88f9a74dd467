#!/usr/bin/env bash
# The k-d gather's default (isotropic) path against an older ind_kdgather.c, side by side in one
# process (the anisotropic kernel must not cost the baseline). Compiles the old file
# (git show REV:engine/indirect/ind_kdgather.c, symbols renamed; a revision from before the
# engine's rooms cannot be compiled against today's headers) and bench/kdgather_speed.c against this
# build's engine library, then alternates the two gathers on one synthetic frame (a 256² view
# of a plane, 32,768 photons, r 0.1) and prints the ratio new/old of the median times; the
# images must agree bit for bit. Usage: bench/kdgather-speed.sh [REV] (default main).
set -euo pipefail
cd "$(dirname "$0")/.."
REV=${1:-main}
W=$(mktemp -d)
{ git show "$REV:engine/indirect/ind_kdgather.c" 2>/dev/null || git show "$REV:engine/indirect/kdgather.c"; } > "$W/kdgather_old.c"
REN="-Dkd_gather=kd_gather_old -Dkd_tree_build=kd_tree_build_old -Dkd_tree_free=kd_tree_free_old
     -Dkd_tree_range=kd_tree_range_old -Dkd_gather_point=kd_gather_point_old
     -Dind_kdgather_method=ind_kdgather_method_old"
FLAGS="-Wall -Wextra -O2 -g -DNDEBUG -fopenmp -ffp-contract=off -fno-fast-math -std=c11 -Ibuild/engine"
for room in core kernel scene gl frame trace passes indirect; do FLAGS="$FLAGS -Iengine/$room"; done
gcc $FLAGS $REN -c "$W/kdgather_old.c" -o "$W/old.o"
gcc $FLAGS -c engine/indirect/ind_kdgather.c -o "$W/new.o"
gcc $FLAGS -c bench/kdgather_speed.c -o "$W/main.o"
gcc -fopenmp "$W/main.o" "$W/old.o" "$W/new.o" -lm -o "$W/kdgather_speed"
"$W/kdgather_speed"
rm -rf "$W"
