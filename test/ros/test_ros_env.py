"""maru_planner.ros.env: nodes keep the user's DDS networking; loopback only when nothing is set."""

from __future__ import annotations

import os

import pytest

from maru_planner.ros import env


@pytest.fixture
def no_network_settings(monkeypatch):
    for name in (*env.NETWORK_VARIABLES, env.QOS_FROM_XML):
        monkeypatch.delenv(name, raising=False)
    return monkeypatch


def test_nothing_set_falls_back_to_loopback_and_says_so(no_network_settings):
    line = env.network_from_environment()
    assert "loopback only" in line and "ROS_AUTOMATIC_DISCOVERY_RANGE" in line
    assert os.environ["ROS_AUTOMATIC_DISCOVERY_RANGE"] == "LOCALHOST"
    assert os.environ["FASTRTPS_DEFAULT_PROFILES_FILE"].endswith(env.LOOPBACK_PROFILE)
    assert os.environ[env.QOS_FROM_XML] == "1"  # the profile's DYNAMIC history memory takes effect


def test_loopback_keeps_a_users_qos_from_xml_choice(no_network_settings):
    no_network_settings.setenv(env.QOS_FROM_XML, "0")
    env.network_from_environment()
    assert os.environ[env.QOS_FROM_XML] == "0"


@pytest.mark.parametrize(
    ("name", "value"),
    [
        ("RMW_IMPLEMENTATION", "rmw_cyclonedds_cpp"),
        ("ROS_AUTOMATIC_DISCOVERY_RANGE", "SUBNET"),
        ("ROS_LOCALHOST_ONLY", "0"),
        ("FASTDDS_DEFAULT_PROFILES_FILE", "/etc/robot/dds.xml"),
        ("FASTRTPS_DEFAULT_PROFILES_FILE", "/etc/robot/dds.xml"),
        ("ROS_STATIC_PEERS", "192.168.1.20"),
        ("ROS_DOMAIN_ID", "42"),
    ],
)
def test_any_user_setting_is_kept_and_nothing_is_added(no_network_settings, name, value):
    no_network_settings.setenv(name, value)
    line = env.network_from_environment()
    assert f"{name}={value}" in line
    assert env.user_network_settings() == {name: value}  # nothing changed, nothing added


def test_our_runs_keep_an_exported_domain_id_and_otherwise_pick_one(no_network_settings):
    no_network_settings.setenv("ROS_DOMAIN_ID", "42")
    assert env.configure_loopback_dds(random_domain=True) == env.loopback_dds_environment()
    assert os.environ["ROS_DOMAIN_ID"] == "42"
    assert os.environ["ROS_AUTOMATIC_DISCOVERY_RANGE"] == "LOCALHOST"
    no_network_settings.delenv("ROS_DOMAIN_ID")
    env.configure_loopback_dds(random_domain=True)
    assert 1 <= int(os.environ["ROS_DOMAIN_ID"]) <= 100
    assert env.configure_loopback_dds(7)["ROS_DOMAIN_ID"] == "7"
