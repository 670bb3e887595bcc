#!/usr/bin/env bash
# Benchmarks: installs the peers (npm packages lindenmayer and @dgreenheck/ez-tree, pinned in
# samples/bench/), builds bench_lsystem, bench_stems, bench_tess, bench_foliage,
# bench_leaf_lod (leaves on the GL backend, headless) and bench_forest (forests of 1 to 100 000
# trees on the GL backend) in Release
# and runs them one after the other; the figures go to the terminal and to
# $BUILD_DIR/<name>.txt, bench_tess's rows also to $BUILD_DIR/bench_tess.dat (+ .front), plotted
# by gnuplot into $BUILD_DIR/bench_tess.png, and bench_foliage's comparison with meshoptimizer
# to $BUILD_DIR/bench_foliage.dat and .png. docs/BENCHMARKS.md explains the tables.
#
#   scripts/bench.sh                 # full sizes (a few minutes)
#   scripts/bench.sh --quick         # smoke sizes; options are passed to both benchmarks
#   BUILD_DIR=build-foo scripts/bench.sh
#
# bench_lsystem and bench_stems take --quick, --no-peer, --repeats N and --node PATH
# (--peer-script would name one script for both: run the binaries directly for that);
# bench_tess, bench_foliage, bench_leaf_lod and bench_forest get --quick only (bench_tess has
# no peer; bench_foliage's is meshoptimizer, linked in when libmeshoptimizer-dev is installed).
#
# Without node/npm it tries apt-get (Debian/Ubuntu); if that is not possible the benchmark still
# runs and reports the peer as not available.
set -euo pipefail
cd "$(dirname "$0")/.."

BUILD_DIR="${BUILD_DIR:-build-release}"
PEER_DIR=samples/bench

have_node() { command -v node >/dev/null 2>&1 && command -v npm >/dev/null 2>&1; }

install_node() {
    have_node && return 0
    if ! command -v apt-get >/dev/null 2>&1; then
        echo "bench.sh: no node/npm and no apt-get" >&2
        return 1
    fi
    local sudo=""
    if [ "$(id -u)" -ne 0 ]; then
        if ! command -v sudo >/dev/null 2>&1; then
            echo "bench.sh: need root to install nodejs" >&2
            return 1
        fi
        sudo=sudo
    fi
    echo "bench.sh: installing nodejs and npm with apt-get"
    $sudo apt-get update -qq && $sudo apt-get install -y -qq nodejs npm
}

# npm ci only when node_modules is missing or older than the lock file.
install_peer() {
    local stamp="$PEER_DIR/node_modules/.package-lock.json"
    if [ -f "$stamp" ] && [ ! "$PEER_DIR/package-lock.json" -nt "$stamp" ]; then
        return 0
    fi
    echo "bench.sh: npm ci in $PEER_DIR"
    (cd "$PEER_DIR" && npm ci --no-audit --no-fund --loglevel=error)
}

if install_node && install_peer; then
    :
else
    echo "bench.sh: continuing without the node peers" >&2
fi

# The generator is only chosen for a fresh build folder; an existing one keeps its own.
generator=()
if [ ! -f "$BUILD_DIR/CMakeCache.txt" ] && command -v ninja >/dev/null 2>&1; then
    generator=(-G Ninja)
fi
cmake -S . -B "$BUILD_DIR" "${generator[@]}" -DCMAKE_BUILD_TYPE=Release >/dev/null
cmake --build "$BUILD_DIR" --target bench_lsystem bench_stems bench_tess bench_foliage bench_leaf_lod \
    bench_forest

if commit="$(git rev-parse --short HEAD 2>/dev/null)"; then
    git diff --quiet HEAD || commit="$commit (with local changes)"
else
    commit=unknown
fi
cpu="$(lscpu 2>/dev/null | sed -n 's/^Model name:[[:space:]]*//p' || true)"

# run_bench NAME ARGS...: runs $BUILD_DIR/samples/NAME, tees into $BUILD_DIR/NAME.txt, and
# returns its exit status.
run_bench() {
    local name="$1"
    shift
    local results="$BUILD_DIR/$name.txt"
    set +e
    {
        echo "date:    $(date -u '+%Y-%m-%d %H:%M UTC')"
        echo "commit:  $commit"
        echo "cpu:     ${cpu:-unknown}, $(nproc 2>/dev/null || echo '?') cores"
        echo "node:    $(node --version 2>/dev/null || echo 'not installed')"
        echo "command: $BUILD_DIR/samples/$name $*"
        echo
        "$BUILD_DIR/samples/$name" "$@"
    } 2>&1 | tee "$results"
    local rc=${PIPESTATUS[0]}
    set -e
    echo
    echo "bench.sh: results written to $results (exit status $rc)"
    return "$rc"
}

status=0
run_bench bench_lsystem "$@" || status=$?
echo
run_bench bench_stems "$@" || status=$?
echo
tess_args=(--dat "$BUILD_DIR/bench_tess.dat")
for a in "$@"; do [ "$a" = --quick ] && tess_args+=(--quick); done
if run_bench bench_tess "${tess_args[@]}"; then
    if command -v gnuplot >/dev/null 2>&1; then
        gnuplot -e "dat='$BUILD_DIR/bench_tess.dat'; out='$BUILD_DIR/bench_tess.png'" \
            scripts/plot_tess.gp && echo "bench.sh: plot written to $BUILD_DIR/bench_tess.png"
    fi
else
    status=$?
fi
echo
foliage_args=(--dat "$BUILD_DIR/bench_foliage.dat")
for a in "$@"; do [ "$a" = --quick ] && foliage_args+=(--quick); done
if run_bench bench_foliage "${foliage_args[@]}"; then
    if command -v gnuplot >/dev/null 2>&1; then
        gnuplot -e "dat='$BUILD_DIR/bench_foliage.dat'; out='$BUILD_DIR/bench_foliage.png'" \
            scripts/plot_foliage.gp && echo "bench.sh: plot written to $BUILD_DIR/bench_foliage.png"
    fi
else
    status=$?
fi
echo
leaf_args=()
for a in "$@"; do [ "$a" = --quick ] && leaf_args+=(--quick); done
run_bench bench_leaf_lod "${leaf_args[@]}" || status=$?
echo
run_bench bench_forest "${leaf_args[@]}" || status=$?
exit "$status"
