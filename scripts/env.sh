# Sourced by the scripts: installs lavapipe when no Vulkan driver for it is present and sets
# the environment Mesa and wgpu want.

as_root() { if [ "$(id -u)" -eq 0 ]; then "$@"; else sudo "$@"; fi; }

if ! ls /usr/share/vulkan/icd.d/lvp_icd*.json >/dev/null 2>&1; then
  echo "== installing mesa-vulkan-drivers (lavapipe)"
  as_root apt-get update -qq
  DEBIAN_FRONTEND=noninteractive as_root apt-get install -y -qq mesa-vulkan-drivers >/dev/null
fi

# Mesa wants a private runtime dir; keep its shader cache inside target/.
export XDG_RUNTIME_DIR="${XDG_RUNTIME_DIR:-/tmp/rae-xdg-$(id -u)}"
mkdir -p -m 0700 "$XDG_RUNTIME_DIR"
export MESA_SHADER_CACHE_DIR="${MESA_SHADER_CACHE_DIR:-$PWD/target/mesa_shader_cache}"
export OMP_WAIT_POLICY=PASSIVE
