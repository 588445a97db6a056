"""The BARN Challenge in MuJoCo: the base stack (online costmap, global planner, elastic strip) driving a
simulated Jackal, scored like the challenge."""
