"""Keep every DDS participant of maru_planner on loopback.

Call :func:`configure_loopback_dds` before ``rclpy.init`` in every entry point
(nodes, demo, benchmarks); tests do it once in ``test/conftest.py``. Imports no
rclpy, so it is safe to call first thing.
"""

from __future__ import annotations

import os
import random

from maru_planner.paths import config_path

LOOPBACK_PROFILE = "fastdds_loopback.xml"


def loopback_dds_environment(domain_id: int | None = None) -> dict[str, str]:
    """The environment variables that confine DDS to 127.0.0.1."""
    env = {
        "ROS_AUTOMATIC_DISCOVERY_RANGE": "LOCALHOST",
        "FASTRTPS_DEFAULT_PROFILES_FILE": str(config_path(LOOPBACK_PROFILE)),
        "RMW_IMPLEMENTATION": "rmw_fastrtps_cpp",
    }
    if domain_id is not None:
        env["ROS_DOMAIN_ID"] = str(domain_id)
    return env


def configure_loopback_dds(domain_id: int | None = None, *, random_domain: bool = False) -> dict[str, str]:
    """Set the loopback DDS variables in ``os.environ`` and return them.

    The discovery range and profile are always forced (traffic to any other
    address is never wanted). The domain id is taken from ``domain_id``, else a
    random one in 1..100 when ``random_domain``, else left as inherited.
    """
    if domain_id is None and random_domain:
        domain_id = random.SystemRandom().randint(1, 100)
    env = loopback_dds_environment(domain_id)
    os.environ.update(env)
    os.environ.pop("ROS_LOCALHOST_ONLY", None)
    os.environ.pop("ROS_STATIC_PEERS", None)
    return env
