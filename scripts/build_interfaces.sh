#!/usr/bin/env bash
# Build the interface packages under interfaces/ with cmake from the ROS 2 wheels and install them into the
# venv: maru_planner_interfaces, tf2_msgs (a minimal TFMessage-only stand-in, for mujoco_sim_node's /tf) unless a
# real tf2_msgs is already importable, and control_msgs (FollowJointTrajectory only, for arm_sim_node and
# planning_node's execute path) unless a real control_msgs is already importable. Idempotent: each is skipped
# when its sources are unchanged.
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
venv=${VENV:-$root/.venv}
py=$venv/bin/python3
unset _ROS_WHEELS_BOOTSTRAP_COMPLETE

# one build at a time (make setup, a colcon test, a helper): they share build/ and the venv
mkdir -p "$root/build"
exec 9>"$root/build/.maru_interfaces.lock"
flock 9

wheels_sourced=0
# build_package NAME CHECK STAMP: cmake-build interfaces/NAME into the venv unless its stamp matches and the Python
# statement CHECK runs
build_package() {
  local name=$1 check=$2 stamp=$3
  local src=$root/interfaces/$name build=$root/build/$name
  local hash
  hash=$(cd "$src" && shopt -s nullglob && cat CMakeLists.txt package.xml msg/*.msg srv/*.srv action/*.action \
    | sha256sum | cut -d' ' -f1)
  if [ -f "$stamp" ] && [ "$(cat "$stamp")" = "$hash" ] && "$py" -c "$check" 2>/dev/null; then
    echo "$name: up to date"
    return 0
  fi
  mkdir -p "$build"
  echo "$name: building (about 10 s)"
  if [ "$wheels_sourced" = 0 ]; then
    # shellcheck source=scripts/wheels_env.sh
    source "$root/scripts/wheels_env.sh"
    wheels_sourced=1
  fi
  cmake -S "$src" -B "$build" -DCMAKE_INSTALL_PREFIX="$venv" -DCMAKE_PREFIX_PATH="$venv" \
    -DPython3_EXECUTABLE="$py" -DBUILD_TESTING=OFF -DCMAKE_BUILD_TYPE=Release >"$build/build.log" 2>&1 \
    || { tail -40 "$build/build.log"; exit 1; }
  cmake --build "$build" -j "$(nproc)" >>"$build/build.log" 2>&1 || { tail -40 "$build/build.log"; exit 1; }
  cmake --install "$build" --prefix "$venv" >>"$build/build.log" 2>&1 || { tail -40 "$build/build.log"; exit 1; }
  "$py" -c "$check" || { echo "built, but Python cannot run: $check"; exit 1; }
  echo "$hash" > "$stamp"
  echo "$name: installed into $venv"
}

build_package maru_planner_interfaces "import maru_planner_interfaces.srv" "$venv/.maru_interfaces.stamp"
# a real tf2_msgs (a ROS installation, a future wheel) wins; ours only fills the gap
if [ -f "$venv/.maru_tf2_msgs.stamp" ] || ! "$py" -c "import tf2_msgs.msg" 2>/dev/null; then
  build_package tf2_msgs "import tf2_msgs.msg" "$venv/.maru_tf2_msgs.stamp"
else
  echo "tf2_msgs: provided by the installation"
fi
# likewise control_msgs: FollowJointTrajectory, upstream's text (same type hashes as a ros2_control install); the
# class is imported, not just the package (a leftover directory imports as an empty namespace package)
fjt="from control_msgs.action import FollowJointTrajectory"
if [ -f "$venv/.maru_control_msgs.stamp" ] || ! "$py" -c "$fjt" 2>/dev/null; then
  build_package control_msgs "$fjt" "$venv/.maru_control_msgs.stamp"
else
  echo "control_msgs: provided by the installation"
fi
