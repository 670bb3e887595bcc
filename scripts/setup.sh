#!/usr/bin/env bash
# Installs the Debian 12 packages xylem needs to build, test and fuzz, and the npm package of the
# glTF-Validator in tests/gltf. Idempotent: when everything is present it prints nothing and
# touches nothing. Run as root (or with sudo).
set -euo pipefail

packages=(
  cmake ninja-build pkg-config gcc g++ make git
  clang libclang-rt-14-dev   # ASan/UBSan and libFuzzer runtimes for clang 14
  libcmocka-dev              # test framework
  libosd-dev                 # OpenSubdiv 3.5 (Far), for stems/ subdivision
  libdragonbox-dev           # shortest round-trip float text (OBJ, .skel, glTF JSON)
  libepoxy-dev libegl-dev libegl1-mesa-dev libgl1-mesa-dri   # GL 4.5 backend, EGL headless (llvmpipe)
  libvulkan-dev mesa-vulkan-drivers vulkan-validationlayers   # Vulkan backend (lavapipe), validation
  glslang-tools spirv-tools  # shaders: GLSL -> SPIR-V and validation at build time
  libpng-dev                 # xylem render writes PNG (samples only)
  libglfw3-dev xvfb xauth    # xylem view: GL in a GLFW window; tests run it under Xvfb
  libimgui-dev               # xylem view's tuning panel (Dear ImGui 1.86; samples only, optional)
  libtinygltf-dev nlohmann-json3-dev   # xylem render --mesh reads .glb (samples only)
  gnuplot-nox                # docs/ plots from bench_tess and bench_foliage (scripts/bench.sh)
  libmeshoptimizer-dev       # bench_foliage's peer (samples only)
  locales                    # a decimal-comma locale for the writers' locale tests
)

missing=()
for p in "${packages[@]}"; do
  if ! dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed"; then
    missing+=("$p")
  fi
done
# node and npm run the Khronos glTF-Validator (tests/gltf). A node that is already there, from
# whatever source, is kept: Debian's npm would conflict with a node that bundles its own.
if ! command -v node >/dev/null 2>&1; then
  missing+=(nodejs npm)
elif ! command -v npm >/dev/null 2>&1; then
  missing+=(npm)
fi

sudo_cmd=()
[ "$(id -u)" -eq 0 ] || sudo_cmd=(sudo)
if [ ${#missing[@]} -gt 0 ]; then
  echo "setup: installing ${missing[*]}"
  export DEBIAN_FRONTEND=noninteractive
  "${sudo_cmd[@]}" apt-get update -qq
  "${sudo_cmd[@]}" apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
fi

# The writers must print '.' whatever the locale: their tests switch to de_DE, which a fresh
# machine does not have compiled.
if ! locale -a 2>/dev/null | grep -qix 'de_DE.utf-\?8'; then
  echo "setup: compiling the de_DE.UTF-8 locale (for the locale tests)"
  "${sudo_cmd[@]}" localedef -i de_DE -f UTF-8 de_DE.UTF-8
fi

# The glTF-Validator at the version tests/gltf/package-lock.json pins. npm writes
# node_modules/.package-lock.json last, so it stamps a finished install; a newer lock file (a
# version bump) or a missing stamp reinstalls.
gltf_dir="$(cd "$(dirname "$0")/../tests/gltf" && pwd)"
stamp="$gltf_dir/node_modules/.package-lock.json"
if [ ! -f "$stamp" ] || [ "$gltf_dir/package-lock.json" -nt "$stamp" ]; then
  echo "setup: installing the glTF-Validator (npm ci in tests/gltf)"
  (cd "$gltf_dir" && npm ci --no-audit --no-fund --loglevel=error >/dev/null)
fi
