#!/usr/bin/env bash
# Regenerates tests/data/state_format1_paper_rve.bin: a checkpoint saved by mesorve 0.1.0
# (state format 1) for tests/ffi.rs, which checks that later versions still load it.
# Builds the library at the last commit that wrote format 1 in a temporary worktree, then a
# small C program against it: scenes/paper_rve.toml, one committed update to
# [1.5e-4, 0, 0], rve_state_save. Not run by the test suite (the file is committed).
set -euo pipefail
cd "$(dirname "$0")/.."
commit=78c4f2c   # main with state format 1 (before the history kept delta_max only)
work=$(mktemp -d)
trap 'git worktree remove --force "$work/src" >/dev/null 2>&1 || true; rm -rf "$work"' EXIT
git worktree add --detach "$work/src" "$commit" >/dev/null
(cd "$work/src" && cargo build --release --lib --quiet)
cat >"$work/save.c" <<'C'
#include <stdio.h>
#include <stdlib.h>
#include "rve.h"
int main(int argc, char **argv) {
  RveHandle h;
  double eps[3] = {1.5e-4, 0.0, 0.0}, sig[3], d[9];
  size_t size = 0, written = 0;
  if (argc != 3 || rve_init_file(argv[1], &h) != RVE_STATUS_OK) return 1;
  if (rve_update(h, eps, sig, d, RVE_TANGENT_REQUEST_CONSISTENT) != RVE_STATUS_OK) return 2;
  if (rve_commit(h) != RVE_STATUS_OK || rve_state_size(h, &size) != RVE_STATUS_OK) return 3;
  unsigned char *buf = malloc(size);
  if (!buf || rve_state_save(h, buf, size, &written) != RVE_STATUS_OK) return 4;
  FILE *f = fopen(argv[2], "wb");
  if (!f || fwrite(buf, 1, written, f) != written || fclose(f) != 0) return 5;
  free(buf);
  rve_free(h);
  return 0;
}
C
# The library's soname is librve.so.<abi>: stage it under that name, as build-c-examples does.
abi=$(sed -n 's/^#define RVE_ABI_VERSION \([0-9]*\)$/\1/p' "$work/src/include/rve.h")
mkdir -p "$work/lib"
cp "$work/src/target/release/librve.so" "$work/lib/librve.so.$abi"
ln -s "librve.so.$abi" "$work/lib/librve.so"
cc -std=c99 -Wall -Wextra -Werror -I"$work/src/include" "$work/save.c" \
   -L"$work/lib" -lrve -Wl,-rpath,"$work/lib" -o "$work/save"
"$work/save" scenes/paper_rve.toml tests/data/state_format1_paper_rve.bin
echo "wrote tests/data/state_format1_paper_rve.bin ($(wc -c <tests/data/state_format1_paper_rve.bin) bytes, format 1)"
