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

hash=$(cd "$src" && cat CMakeLists.txt package.xml msg/*.msg srv/*.srv action/*.action | sha256sum | cut -d' ' -f1)
if [ -f "$stamp" ] && [ "$(cat "$stamp")" = "$hash" ] \
   && "$py" -c "import maru_planner_interfaces.srv" 2>/dev/null; then
  echo "maru_planner_interfaces: up to date"
  exit 0
fi

# The msg wheels' CMake exports name the wheel builder's Python and numpy include
# dirs; point them at this venv's.
py_inc=$("$py" -c "import sysconfig; print(sysconfig.get_paths()['include'])")
np_inc=$("$py" -c "import numpy; print(numpy.get_include())")
for f in "$venv"/share/*/cmake/*__rosidl_generator_pyExport.cmake; do
  if grep -q "/opt/python/cp311-cp311" "$f"; then
    sed -i -e "s#/opt/python/cp311-cp311/include/python3.11#$py_inc#g" \
           -e "s#/opt/python/cp311-cp311/lib/python3.11/site-packages/numpy/_core/include#$np_inc#g" "$f"
  fi
done

mkdir -p "$build"
echo "maru_planner_interfaces: building (about 10 s)"
export PATH="$venv/bin:$PATH"
# The wheels ship their shared libraries under the venv; cmake-run generators need them.
ros_libs=$("$py" - <<'PY'
import glob, os, sys
site = [p for p in sys.path if p.endswith("site-packages")][0]
dirs = {os.path.dirname(p) for p in glob.glob(os.path.join(sys.prefix, "lib", "*.so*"))}
dirs |= {os.path.dirname(p) for p in glob.glob(os.path.join(site, "**", "lib", "*.so*"), recursive=False)}
print(":".join(sorted(dirs)))
PY
)
export LD_LIBRARY_PATH="$venv/lib:${ros_libs}:${LD_LIBRARY_PATH:-}"
cmake -S "$src" -B "$build" -DCMAKE_INSTALL_PREFIX="$venv" -DCMAKE_PREFIX_PATH="$venv" \
  -DPython3_EXECUTABLE="$py" -DBUILD_TESTING=OFF -DCMAKE_BUILD_TYPE=Release >"$build/build.log" 2>&1 \
  || { tail -40 "$build/build.log"; exit 1; }
cmake --build "$build" -j "$(nproc)" >>"$build/build.log" 2>&1 || { tail -40 "$build/build.log"; exit 1; }
cmake --install "$build" >>"$build/build.log" 2>&1 || { tail -40 "$build/build.log"; exit 1; }
"$py" -c "import maru_planner_interfaces.srv" || { echo "built, but Python cannot import maru_planner_interfaces"; exit 1; }
echo "$hash" > "$stamp"
echo "maru_planner_interfaces: installed into $venv"
