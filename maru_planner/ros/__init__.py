"""ROS 2 adapters: nodes and message conversions only (the core lives elsewhere)."""
