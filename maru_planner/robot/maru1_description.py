"""Old home of Maru-1's description, now in :mod:`maru_planner.robot.robots.maru1` (re-exported here).

Still the command the generated files name in their header::

    python -m maru_planner.robot.maru1_description          # regenerate urdf/maru1_upper_body.{urdf,srdf}
    python -m maru_planner.robot.maru1_description --check  # exit 1 if the files are stale

(``python -m`` of this module rather than of ``robots/maru1.py``: importing the ``maru_planner.robot``
package loads ``robots/maru1.py`` before it could run as ``__main__``.)
"""

from maru_planner.robot.robots.maru1 import (
    ACCELERATION_LIMIT,
    ARM_DOWN,
    ARM_JOINTS,
    D_2,
    D_U,
    DISABLED_PAIR_SAMPLES,
    DISABLED_PAIR_SEED,
    EFFORT,
    GROUPS,
    HALF_PI,
    JOINT_LIMITS,
    L_0,
    L_1,
    L_3,
    L_5,
    L_6,
    L_U,
    MOUNT_JOINTS,
    NAMED_STATES,
    PRINTED_THETA0,
    DHRow,
    arm_rows,
    body_row,
    collision_geometry,
    dh_matrix,
    generate,
    generate_srdf,
    generate_urdf,
    joint_limit,
    main,
)

__all__ = [
    "ACCELERATION_LIMIT",
    "ARM_DOWN",
    "ARM_JOINTS",
    "D_2",
    "D_U",
    "DISABLED_PAIR_SAMPLES",
    "DISABLED_PAIR_SEED",
    "EFFORT",
    "GROUPS",
    "HALF_PI",
    "JOINT_LIMITS",
    "L_0",
    "L_1",
    "L_3",
    "L_5",
    "L_6",
    "L_U",
    "MOUNT_JOINTS",
    "NAMED_STATES",
    "PRINTED_THETA0",
    "DHRow",
    "arm_rows",
    "body_row",
    "collision_geometry",
    "dh_matrix",
    "generate",
    "generate_srdf",
    "generate_urdf",
    "joint_limit",
    "main",
]

if __name__ == "__main__":
    raise SystemExit(main())
