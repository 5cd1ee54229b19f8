#!/usr/bin/env bash
# Per-call times of RNEA, CRBA and ABA: lsdc beside Pinocchio, on the same URDF robots.
#
#   bash bench/speed_vs_pinocchio.sh [ROBOT.urdf ...]
#
# Default robots: UR5, Panda and Talos reduced, the URDF files bench/pinocchio_fixtures.py copies
# from example-robot-data (tests/fixtures/urdf/, or bench/urdf/ for a file over 300 KB).
#
# Pinocchio's side is bench/pinocchio_speed.cpp, compiled here with g++ -O3 -DNDEBUG against the
# pip-installed Pinocchio (`pip install pin`), header-only templates instantiated in the
# benchmark itself, no -march=native: lsdc is compiled by `cargo --release` without target-cpu,
# so both sides are portable x86-64 code. lsdc's side is `cargo bench --bench pinocchio_peer`
# (benches/pinocchio_peer.rs). Both print one line per robot, `ROBOT rnea_ns crba_ns aba_ns nv`:
# fixed base, a few hundred random states cycled, best of 7 batches of about 20 ms.
#
# Pinocchio's headers need Eigen's and urdfdom's, which `pip install pin` does not bring:
#   pip install cmeel-eigen cmeel-urdfdom-headers      (or apt-get install libeigen3-dev)
# The compile takes about two minutes; its result is kept in target/pinocchio_speed/.
# Environment: PYTHON (default python3), CXX (default g++).

set -euo pipefail
cd "$(dirname "$0")/.."

PYTHON=${PYTHON:-python3}
CXX=${CXX:-g++}

fail() {
    echo "error: $*" >&2
    exit 2
}

# --- Robots ---------------------------------------------------------------------------------
find_urdf() {
    for dir in tests/fixtures/urdf bench/urdf; do
        if [ -f "$dir/$1.urdf" ]; then
            echo "$dir/$1.urdf"
            return
        fi
    done
    fail "no $1.urdf in tests/fixtures/urdf or bench/urdf: run python3 bench/pinocchio_fixtures.py first"
}
if [ "$#" -gt 0 ]; then
    ROBOTS=("$@")
else
    ROBOTS=("$(find_urdf ur5)" "$(find_urdf panda)" "$(find_urdf talos_reduced)")
fi
for urdf in "${ROBOTS[@]}"; do
    [ -f "$urdf" ] || fail "no URDF file \`$urdf\`"
done

# --- Pinocchio, installed by pip ------------------------------------------------------------
command -v "$PYTHON" >/dev/null || fail "no \`$PYTHON\`: Pinocchio is found through its pip package (set PYTHON)"
if ! "$PYTHON" -c "import pinocchio" 2>/dev/null; then
    fail "Pinocchio is not installed for $PYTHON: pip install pin"
fi
PREFIX=$("$PYTHON" - <<'EOF'
import pathlib, sys
try:
    import cmeel
except ImportError:
    sys.exit(0)
print(pathlib.Path(cmeel.__file__).resolve().parent.parent / "cmeel.prefix")
EOF
)
[ -n "$PREFIX" ] && [ -d "$PREFIX" ] || fail "Pinocchio's C++ files were not found (expected pip's cmeel.prefix): pip install pin"
PIN_VERSION=$("$PYTHON" -c "import pinocchio; print(pinocchio.__version__)")
[ -f "$PREFIX/include/pinocchio/algorithm/rnea.hpp" ] || fail "no Pinocchio headers under $PREFIX/include: pip install pin"
[ -e "$PREFIX/lib/libpinocchio_default.so" ] || fail "no libpinocchio_default.so under $PREFIX/lib: pip install pin"
[ -e "$PREFIX/lib/libpinocchio_parsers.so" ] || fail "no libpinocchio_parsers.so under $PREFIX/lib: pip install pin"

INCLUDES=(-I"$PREFIX/include")
if [ -f "$PREFIX/include/eigen3/Eigen/Core" ]; then
    INCLUDES+=(-I"$PREFIX/include/eigen3")
elif [ -f /usr/include/eigen3/Eigen/Core ]; then
    INCLUDES+=(-I/usr/include/eigen3)
else
    fail "Eigen's headers are missing (Pinocchio's headers need them): pip install cmeel-eigen (or apt-get install libeigen3-dev)"
fi
if [ -f "$PREFIX/include/urdfdom_headers/urdf_model/model.h" ]; then
    INCLUDES+=(-I"$PREFIX/include/urdfdom_headers")
elif [ ! -f "$PREFIX/include/urdf_model/model.h" ] && [ ! -f /usr/include/urdf_model/model.h ]; then
    fail "urdfdom's headers are missing (pinocchio/parsers/urdf.hpp needs them): pip install cmeel-urdfdom-headers"
fi
command -v "$CXX" >/dev/null || fail "no C++ compiler \`$CXX\` (apt-get install g++)"

# The definitions Pinocchio's CMake targets give their users (pinocchio::pinocchio_parsers).
DEFINES=(
    -DNDEBUG
    -DPINOCCHIO_WITH_URDFDOM
    -DPINOCCHIO_URDFDOM_HEADERS_MAJOR_VERSION=3
    -DPINOCCHIO_URDFDOM_HEADERS_MINOR_VERSION=0
    -DPINOCCHIO_URDFDOM_HEADERS_PATCH_VERSION=0
    -DBOOST_MPL_LIMIT_LIST_SIZE=30
    -DBOOST_MPL_LIMIT_VECTOR_SIZE=30
    -DBOOST_MPL_CFG_NO_PREPROCESSED_HEADERS
    -DBOOST_FUSION_INVOKE_MAX_ARITY=12
)
FLAGS=(-std=c++17 -O3 "${DEFINES[@]}" "${INCLUDES[@]}")
LIBS=(-L"$PREFIX/lib" -Wl,-rpath,"$PREFIX/lib" -lpinocchio_parsers -lpinocchio_default -lurdfdom_model)

OUT=target/pinocchio_speed
BIN=$OUT/pinocchio_speed
STAMP=$OUT/flags
mkdir -p "$OUT"
WANTED="$CXX ${FLAGS[*]} ${LIBS[*]} pinocchio $PIN_VERSION"
if [ ! -x "$BIN" ] || [ bench/pinocchio_speed.cpp -nt "$BIN" ] || [ "$(cat "$STAMP" 2>/dev/null)" != "$WANTED" ]; then
    echo "compiling bench/pinocchio_speed.cpp against Pinocchio $PIN_VERSION (about two minutes)..." >&2
    "$CXX" "${FLAGS[@]}" bench/pinocchio_speed.cpp -o "$BIN" "${LIBS[@]}" || fail "the Pinocchio benchmark does not compile"
    echo "$WANTED" > "$STAMP"
fi

# --- Measurements ---------------------------------------------------------------------------
PIN_LINES=$OUT/pinocchio.txt
LSDC_LINES=$OUT/lsdc.txt
: > "$PIN_LINES"
: > "$LSDC_LINES"
for urdf in "${ROBOTS[@]}"; do
    echo "Pinocchio: $urdf" >&2
    "$BIN" "$urdf" | tee -a "$PIN_LINES" >&2
done

echo "lsdc: cargo bench --bench pinocchio_peer -- ${ROBOTS[*]}" >&2
if [ ! -f benches/pinocchio_peer.rs ]; then
    echo "note: benches/pinocchio_peer.rs does not exist yet: lsdc's column stays empty" >&2
elif ! cargo bench --bench pinocchio_peer -- "${ROBOTS[@]}" > "$LSDC_LINES"; then
    echo "note: \`cargo bench --bench pinocchio_peer\` failed: lsdc's column stays empty" >&2
    : > "$LSDC_LINES"
fi

# --- Table ----------------------------------------------------------------------------------
"$PYTHON" - "$PIN_LINES" "$LSDC_LINES" "$PIN_VERSION" <<'EOF'
import re
import sys

LINE = re.compile(r"^(\S+)\s+([-+0-9.eE]+)\s+([-+0-9.eE]+)\s+([-+0-9.eE]+)\s+(\d+)\s*$")

def read(path):
    rows = {}
    for line in open(path):
        m = LINE.match(line.strip())
        if m:
            rows[m.group(1)] = ([float(m.group(i)) for i in (2, 3, 4)], int(m.group(5)))
    return rows

pin, lsdc, version = read(sys.argv[1]), read(sys.argv[2]), sys.argv[3]
print(f"\nPer-call times in ns (best of 7 batches); ratio = lsdc / Pinocchio {version}")
head = f"{'robot':<16} {'nv':>4}"
for name in ("rnea", "crba", "aba"):
    head += f" | {name + ' lsdc':>10} {'pinocchio':>10} {'ratio':>6}"
print(head)
print("-" * len(head))
for robot, (times, nv) in pin.items():
    row = f"{robot:<16} {nv:>4}"
    mine = lsdc.get(robot)
    for k in range(3):
        ours = f"{mine[0][k]:>10.0f}" if mine else f"{'-':>10}"
        ratio = f"{mine[0][k] / times[k]:>6.2f}" if mine and times[k] > 0 else f"{'-':>6}"
        row += f" | {ours} {times[k]:>10.0f} {ratio}"
    if mine and mine[1] != nv:
        row += f"  (lsdc has nv = {mine[1]})"
    print(row)
for robot in lsdc:
    if robot not in pin:
        print(f"{robot:<16} (lsdc only: {lsdc[robot][0]})")
EOF
