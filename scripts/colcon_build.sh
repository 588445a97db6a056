#!/usr/bin/env bash
# Build both packages of this repository with colcon, against the ROS 2 wheels in the venv.
#   scripts/colcon_build.sh [OUT_DIR]   -> OUT_DIR/{build,install,log} (default: the repository root)
# CMake is re-run every time, so the install goes to OUT_DIR/install even in a build tree another prefix
# configured (build/maru_planner_interfaces of build_interfaces.sh, which colcon then only brings up to date).
# The manifest of maru_planner is the repository root, where colcon's crawl stops: the interfaces are a second base
# path. On a full ROS 2 install, `colcon build --base-paths . interfaces` at the repository root does the same.
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
venv=${VENV:-$root/.venv}
out=${1:-$root}
# shellcheck source=scripts/wheels_env.sh
source "$root/scripts/wheels_env.sh"
cd "$root"
exec "$venv/bin/colcon" --log-base "$out/log" build --base-paths "$root" "$root/interfaces" \
  --build-base "$out/build" --install-base "$out/install" --cmake-force-configure \
  --cmake-args -DPython3_EXECUTABLE="$py" -DBUILD_TESTING=OFF -DCMAKE_BUILD_TYPE=Release
