#!/usr/bin/env bash
# Build both packages of this repository with colcon, against the ROS 2 wheels in the venv.
#   scripts/colcon_build.sh [OUT_DIR]   -> OUT_DIR/{build,install,log} (default: the repository root)
# On a full ROS 2 install, plain `colcon build` in a workspace holding this repository does the same.
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
venv=${VENV:-$root/.venv}
out=${1:-$root}
# shellcheck source=scripts/wheels_env.sh
source "$root/scripts/wheels_env.sh"
cd "$root"
exec "$venv/bin/colcon" --log-base "$out/log" build --base-paths "$root" \
  --build-base "$out/build" --install-base "$out/install" \
  --cmake-args -DPython3_EXECUTABLE="$py" -DBUILD_TESTING=OFF -DCMAKE_BUILD_TYPE=Release
