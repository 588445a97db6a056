"""DDS networking of maru_planner processes: the user's settings for nodes, loopback for our own runs.

- A node's ``main()`` calls :func:`network_from_environment` before ``rclpy.init``: whatever the
  user set (:data:`NETWORK_VARIABLES`: RMW, discovery range, localhost-only, Fast DDS profiles,
  static peers, domain) is left exactly as it is; only when none of them is set does the node
  fall back to the safe local setting (loopback Fast DDS). It returns the line the node logs.
- Tests, the demo, CI and benchmarks call :func:`configure_loopback_dds`: all their own traffic
  stays on 127.0.0.1, whatever the environment says (the nodes they start inherit it).

Imports no rclpy, so it is safe to call first thing.
"""

from __future__ import annotations

import os
import random
import socket

from maru_planner.paths import config_path

LOOPBACK_PROFILE = "fastdds_loopback.xml"

#: Lets rmw_fastrtps take the history memory policy from the profile (see the profile's comment).
QOS_FROM_XML = "RMW_FASTRTPS_USE_QOS_FROM_XML"
#: Loopback settings that a user's own value overrides (everything else of the loopback is forced).
LOOPBACK_DEFAULTS = {QOS_FROM_XML: "1"}

#: The variables through which a user chooses ROS 2 networking; nodes never change them.
NETWORK_VARIABLES = (
    "RMW_IMPLEMENTATION",
    "ROS_AUTOMATIC_DISCOVERY_RANGE",
    "ROS_LOCALHOST_ONLY",
    "FASTRTPS_DEFAULT_PROFILES_FILE",
    "FASTDDS_DEFAULT_PROFILES_FILE",
    "ROS_STATIC_PEERS",
    "ROS_DOMAIN_ID",
)


def loopback_dds_environment(domain_id: int | None = None) -> dict[str, str]:
    """The environment variables that confine DDS to 127.0.0.1."""
    env = {
        "ROS_AUTOMATIC_DISCOVERY_RANGE": "LOCALHOST",
        "FASTRTPS_DEFAULT_PROFILES_FILE": str(config_path(LOOPBACK_PROFILE)),
        "RMW_IMPLEMENTATION": "rmw_fastrtps_cpp",
        **LOOPBACK_DEFAULTS,
    }
    if domain_id is not None:
        env["ROS_DOMAIN_ID"] = str(domain_id)
    return env


def configure_loopback_dds(domain_id: int | None = None, *, random_domain: bool = False) -> dict[str, str]:
    """Set the loopback DDS variables in ``os.environ`` and return them (tests, demo, CI, benchmarks).

    The discovery range and profile are always forced (traffic to any other
    address is never wanted). The domain id is taken from ``domain_id``, else the
    user's exported ``ROS_DOMAIN_ID``, else one in 1..100 that no process on this machine uses
    (:func:`unused_domain_id`) when ``random_domain``, else left unset. :data:`LOOPBACK_DEFAULTS` apply only
    where the user set nothing.
    """
    if domain_id is None and random_domain and not os.environ.get("ROS_DOMAIN_ID"):
        domain_id = unused_domain_id()
    env = loopback_dds_environment(domain_id)
    for name, value in env.items():
        if name not in LOOPBACK_DEFAULTS or not os.environ.get(name):
            os.environ[name] = value
    os.environ.pop("ROS_LOCALHOST_ONLY", None)
    os.environ.pop("ROS_STATIC_PEERS", None)
    return env


def unused_domain_id(participants: int = 4) -> int:
    """A random ROS domain id in 1..100 in which no DDS participant on this machine holds a discovery port (RTPS
    port mapping: participant ``i`` of domain ``d`` takes UDP 7410 + 250 d + 2 i); any one if all are taken."""
    domains = list(range(1, 101))
    random.SystemRandom().shuffle(domains)
    for domain in domains:
        if not any(_udp_port_taken(7410 + 250 * domain + 2 * i) for i in range(participants)):
            return domain
    return domains[0]


def _udp_port_taken(port: int) -> bool:
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as probe:
        try:
            probe.bind(("127.0.0.1", port))
        except OSError:
            return True
    return False


def user_network_settings() -> dict[str, str]:
    """The networking variables set (non-empty) in this process's environment, by name."""
    return {name: os.environ[name] for name in NETWORK_VARIABLES if os.environ.get(name)}


def network_from_environment() -> str:
    """A node's networking, before ``rclpy.init``: the user's settings if any, else loopback; the line to log."""
    settings = user_network_settings()
    if settings:
        chosen = ", ".join(f"{name}={value}" for name, value in settings.items())
        return f"DDS networking from the environment: {chosen}"
    configure_loopback_dds()
    return (
        "DDS networking: no ROS networking variable set, so loopback only "
        f"(ROS_AUTOMATIC_DISCOVERY_RANGE=LOCALHOST, {LOOPBACK_PROFILE}); set any of "
        f"{', '.join(NETWORK_VARIABLES)} to choose your own"
    )
