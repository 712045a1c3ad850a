# Sourced by the scripts: installs lavapipe when no Vulkan driver for it is present and sets
# the environment Mesa and wgpu want.

as_root() { if [ "$(id -u)" -eq 0 ]; then "$@"; else sudo "$@"; fi; }

if ! ls /usr/share/vulkan/icd.d/lvp_icd*.json >/dev/null 2>&1; then
  echo "== installing mesa-vulkan-drivers (lavapipe)"
  as_root apt-get update -qq
  DEBIAN_FRONTEND=noninteractive as_root apt-get install -y -qq mesa-vulkan-drivers >/dev/null
fi

# lavapipe at 512-bit vectors where the CPU has AVX-512 (0.7x the frame time here): what
# rae-cli and rae-trace ask for themselves (rae_core::gpu::prefer_wide_cpu_vectors); exported
# so that the test processes, which open lavapipe directly, run the same code.
if [ -z "${LP_NATIVE_VECTOR_WIDTH:-}" ] && grep -qw avx512f /proc/cpuinfo 2>/dev/null; then
  export LP_NATIVE_VECTOR_WIDTH=512
fi

# Mesa wants a private runtime dir; keep its shader cache inside the repository's target/, one
# per vector width (Mesa 22.3's cache does not key on it and would serve shaders compiled for the
# other). Mesa does not create the cache's parent folders, and without them it caches nothing
# (every rae-cli run compiles its shaders again), so the folder is made here, whichever folder
# this file is sourced from.
export XDG_RUNTIME_DIR="${XDG_RUNTIME_DIR:-/tmp/rae-xdg-$(id -u)}"
mkdir -p -m 0700 "$XDG_RUNTIME_DIR"
export MESA_SHADER_CACHE_DIR="${MESA_SHADER_CACHE_DIR:-$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)/target/mesa_shader_cache-${LP_NATIVE_VECTOR_WIDTH:-default}}"
mkdir -p "$MESA_SHADER_CACHE_DIR"
export OMP_WAIT_POLICY=PASSIVE
