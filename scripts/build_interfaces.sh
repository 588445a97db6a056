#!/usr/bin/env bash
# Build interfaces/maru_planner_interfaces with cmake from the ROS 2 wheels and
# install it into the venv. Idempotent: skipped when the sources are unchanged.
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
venv=${VENV:-$root/.venv}
src=$root/interfaces/maru_planner_interfaces
build=$root/build/maru_planner_interfaces
stamp=$venv/.maru_interfaces.stamp
py=$venv/bin/python3
unset _ROS_WHEELS_BOOTSTRAP_COMPLETE

# one build at a time (make setup, a colcon test, a helper): they share $build and the venv
mkdir -p "$root/build"
exec 9>"$root/build/.maru_interfaces.lock"
flock 9

hash=$(cd "$src" && cat CMakeLists.txt package.xml msg/*.msg srv/*.srv action/*.action | sha256sum | cut -d' ' -f1)
if [ -f "$stamp" ] && [ "$(cat "$stamp")" = "$hash" ] \
   && "$py" -c "import maru_planner_interfaces.srv" 2>/dev/null; then
  echo "maru_planner_interfaces: up to date"
  exit 0
fi

mkdir -p "$build"
echo "maru_planner_interfaces: building (about 10 s)"
# shellcheck source=scripts/wheels_env.sh
source "$root/scripts/wheels_env.sh"
cmake -S "$src" -B "$build" -DCMAKE_INSTALL_PREFIX="$venv" -DCMAKE_PREFIX_PATH="$venv" \
  -DPython3_EXECUTABLE="$py" -DBUILD_TESTING=OFF -DCMAKE_BUILD_TYPE=Release >"$build/build.log" 2>&1 \
  || { tail -40 "$build/build.log"; exit 1; }
cmake --build "$build" -j "$(nproc)" >>"$build/build.log" 2>&1 || { tail -40 "$build/build.log"; exit 1; }
cmake --install "$build" >>"$build/build.log" 2>&1 || { tail -40 "$build/build.log"; exit 1; }
"$py" -c "import maru_planner_interfaces.srv" || { echo "built, but Python cannot import maru_planner_interfaces"; exit 1; }
echo "$hash" > "$stamp"
echo "maru_planner_interfaces: installed into $venv"
