#!/usr/bin/env bash
# Build R2U2 (its C engine and its C2PO specification compiler) outside the repository, for
# the tests and the benchmark that run fretc's `--emit c2po` output through R2U2
# (tests/compiler/test_c2po_r2u2.py, bench/bench_r2u2.py).
#
#   tools/r2u2/build.sh                      # from https://github.com/R2U2/r2u2.git
#   R2U2_GIT=/path/to/r2u2.git tools/r2u2/build.sh   # another URL or git directory
#
# Environment:
#   R2U2_GIT     git URL or git directory of R2U2's source (default: GitHub)
#   R2U2_COMMIT  the commit to build (default: the pinned one below; the tests were run
#                against it)
#   FRETC_TOOLS  where fretc's external tools live (default: ~/.cache/fretc/tools); the
#                build goes to $FRETC_TOOLS/r2u2
#   PYTHON       the Python (3.9 or newer) for C2PO's virtual environment (default: python3)
#   CC           the C compiler for R2U2's Makefile (default: gcc, the Makefile's own)
#
# What it makes under $FRETC_TOOLS/r2u2:
#   src/                  R2U2's compiler/ and monitors/c/ at the pinned commit (sparse)
#   src/monitors/c/build/r2u2   the C engine (`make bin`: R2U2's release build)
#   venv/                 a virtual environment for C2PO (standard library only: nothing
#                         is installed into fretc's own environment)
#   r2u2.env              KEY=value lines the tests read: R2U2_COMMIT, R2U2_ENGINE,
#                         C2PO_SCRIPT, C2PO_PYTHON; written last, so its presence means a
#                         finished build
#
# Nothing of R2U2 is copied into this repository. Running it again rebuilds from scratch.
set -euo pipefail

PINNED=77acb5caccf2f456f8bff33e33cf6c9a8e8b3a32
GIT_SOURCE=${R2U2_GIT:-https://github.com/R2U2/r2u2.git}
COMMIT=${R2U2_COMMIT:-$PINNED}
OUT=${FRETC_TOOLS:-$HOME/.cache/fretc/tools}/r2u2
PY=${PYTHON:-python3}

echo "R2U2 $COMMIT from $GIT_SOURCE into $OUT"
rm -rf "$OUT"
mkdir -p "$OUT"

# Only the two folders the tests use: a sparse, blobless clone (a git directory that lacks
# some large blobs, such as a mirror, still checks these out).
git clone --quiet --no-checkout --filter=blob:none "$GIT_SOURCE" "$OUT/src" 2>/dev/null \
  || git clone --quiet --no-checkout "$GIT_SOURCE" "$OUT/src"
git -C "$OUT/src" sparse-checkout set compiler monitors/c
git -C "$OUT/src" -c advice.detachedHead=false checkout --quiet "$COMMIT"
test "$(git -C "$OUT/src" rev-parse HEAD)" = "$COMMIT"

# The C engine: R2U2's own Makefile, release target (build/r2u2).
make -C "$OUT/src/monitors/c" ${CC:+CC="$CC"} bin >"$OUT/make.log" 2>&1 \
  || { tail -20 "$OUT/make.log"; echo "make failed: $OUT/make.log" >&2; exit 1; }

# C2PO: its own virtual environment (C2PO needs the standard library only at this commit;
# Z3, egglog and Gurobi serve options the tests do not use).
"$PY" -m venv "$OUT/venv"
"$OUT/venv/bin/python" - <<'EOF'
import sys
if sys.version_info < (3, 9):
    raise SystemExit("C2PO needs Python 3.9 or newer")
EOF
"$OUT/venv/bin/python" "$OUT/src/compiler/c2po.py" --version

cat >"$OUT/r2u2.env" <<EOF
R2U2_GIT=$GIT_SOURCE
R2U2_COMMIT=$COMMIT
R2U2_ENGINE=$OUT/src/monitors/c/build/r2u2
C2PO_SCRIPT=$OUT/src/compiler/c2po.py
C2PO_PYTHON=$OUT/venv/bin/python
EOF
echo "built: $OUT/r2u2.env"
