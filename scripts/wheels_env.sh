# Sourced by build_interfaces.sh and colcon_build.sh: the environment that lets cmake and colcon
# build ROS 2 packages against the ROS 2 PyPI wheels installed in $venv (the underlay).
# Expects $venv; sets $py and exports PATH, LD_LIBRARY_PATH, CMAKE_PREFIX_PATH, AMENT_PREFIX_PATH.
py=$venv/bin/python3
unset _ROS_WHEELS_BOOTSTRAP_COMPLETE

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
export CMAKE_PREFIX_PATH="$venv${CMAKE_PREFIX_PATH:+:$CMAKE_PREFIX_PATH}"
export AMENT_PREFIX_PATH="$venv${AMENT_PREFIX_PATH:+:$AMENT_PREFIX_PATH}"
