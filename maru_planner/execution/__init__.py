"""Trajectories executed: joint_trajectory_controller-style interpolation, tolerances, and a simulated arm
that follows them."""
