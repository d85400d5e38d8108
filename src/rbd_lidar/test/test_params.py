"""Parameter drift test: cfg/Zone.cfg keys = config/default.yaml keys = README table = what the node reads."""

import os
import re

import yaml

PKG = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


def read(rel):
    with open(os.path.join(PKG, rel)) as f:
        return f.read()


def cfg_params():
    out = {}
    for m in re.finditer(r'\.add\("(\w+)",\s*(\w+)_t,\s*0,\s*"[^"]*",\s*([^,)]+)', read("cfg/Zone.cfg")):
        name, kind, default = m.group(1), m.group(2), m.group(3).strip()
        out[name] = {"bool": lambda v: v == "True", "int": int, "double": float, "str": str}[kind](default)
    return out


def yaml_params(rel):
    return yaml.safe_load(read(rel))


def readme_params():
    text = read("README.md")
    section = text.split("## Parameters", 1)[1].split("\n## ", 1)[0]
    return set(re.findall(r"^\| `~?(\w+)` \|", section, re.MULTILINE))


def node_params():
    src = read("src/rbd_lidar_node.cpp")
    return set(re.findall(r'param(?:<[\w:]+>)?\("(\w+)"', src))


def test_cfg_keys_and_defaults_match_default_yaml():
    cfg = cfg_params()
    assert len(cfg) >= 19
    y = yaml_params("config/default.yaml")
    for key, default in cfg.items():
        assert key in y, key
        assert y[key] == default, (key, y[key], default)


def test_thesis_defaults():
    y = yaml_params("config/default.yaml")
    assert (y["zone_front"], y["zone_back"], y["zone_left"], y["zone_right"]) == (0.70, 0.55, 0.35, 0.35)
    assert y["blind_zone"] == 0.30
    assert y["reaction_time"] == 0.7
    assert y["stale_periods"] == 3


def test_readme_table_matches_yaml_files():
    keys = set(yaml_params("config/default.yaml")) | set(yaml_params("config/os1_32_beams.yaml"))
    assert readme_params() == keys


def test_node_reads_every_static_key_and_nothing_else():
    static = (set(yaml_params("config/default.yaml")) | set(yaml_params("config/os1_32_beams.yaml"))) - set(
        cfg_params()
    )
    assert node_params() == static


def test_beam_table_is_an_os1_32():
    b = yaml_params("config/os1_32_beams.yaml")
    assert len(b["beam_altitude_angles"]) == 32
    assert len(b["beam_azimuth_angles"]) == 32
    assert len(b["pixel_shift_by_row"]) == 32
    assert b["beam_altitude_angles"] == sorted(b["beam_altitude_angles"], reverse=True)


def test_node_fallback_defaults_equal_yaml():
    """Without the launch file (plain rosrun) the node behaves as with config/default.yaml."""
    y = yaml_params("config/default.yaml")
    y.update(yaml_params("config/os1_32_beams.yaml"))
    src = read("src/rbd_lidar_node.cpp")
    found = 0
    for m in re.finditer(r'param(?:<[\w:]+>)?\("(\w+)", ("[^"]*"|true|false|-?[0-9.]+)\)', src):
        name, literal = m.group(1), m.group(2)
        value = {"true": True, "false": False}.get(literal, literal.strip('"'))
        if isinstance(value, str) and not literal.startswith('"'):
            value = float(value) if "." in value else int(value)
        assert y[name] == value, (name, y[name], value)
        found += 1
    assert found >= 25


def test_builtin_beam_table_equals_yaml():
    b = yaml_params("config/os1_32_beams.yaml")
    src = read("include/rbd_lidar/os1_beams.h")
    alt = [float(v) for v in re.search(r"os1U0Altitudes\(\) \{\s*return \{([^}]*)\}", src).group(1).split(",")]
    assert alt == b["beam_altitude_angles"]
    az = float(re.search(r"std::vector<double>\(32, (-?[0-9.]+)\)", src).group(1))
    assert all(abs(a - az) < 0.02 for a in b["beam_azimuth_angles"])
