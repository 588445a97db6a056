#!/usr/bin/env bash
# Build both packages of this repository with colcon, against the ROS 2 wheels in the venv.
#   scripts/colcon_build.sh [OUT_DIR [BUILD_BASE]]   -> OUT_DIR/{install,log}, BUILD_BASE (default OUT_DIR/build);
#   OUT_DIR defaults to the repository root.
# A BUILD_BASE of <repository>/build builds incrementally on the tree that build_interfaces.sh (make setup)
# compiled: CMake is re-run every time, so the install goes to OUT_DIR/install whatever prefix the tree had.
# On a full ROS 2 install, plain `colcon build` in a workspace holding this repository does the same.
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
venv=${VENV:-$root/.venv}
out=${1:-$root}
build_base=${2:-$out/build}
# shellcheck source=scripts/wheels_env.sh
source "$root/scripts/wheels_env.sh"
cd "$root"
exec "$venv/bin/colcon" --log-base "$out/log" build --base-paths "$root" \
  --build-base "$build_base" --install-base "$out/install" --cmake-force-configure \
  --cmake-args -DPython3_EXECUTABLE="$py" -DBUILD_TESTING=OFF -DCMAKE_BUILD_TYPE=Release
