"""`rbnx demo --lidar-noise`: the deploy copy it boots carries the noise to the simulator and nothing else."""

from __future__ import annotations

from pathlib import Path

import pytest
import yaml

from hal_panda_mobile.config import parse_config
from rbnx.demo.variant import write_variant
from rbnx.models import load_deploy
from robonix_nav_data import resources


def test_variant_sets_the_sim_lidar_noise_and_keeps_the_rest(tmp_path: Path) -> None:
    deploy = resources.example_deploy("sim")
    out = write_variant(deploy, tmp_path / "run", {"lidar_noise": {"noise_std": 0.03, "dropout_prob": 0.05}})
    assert out == tmp_path / "run" / "deploy.yaml"
    orig, raw = yaml.safe_load(deploy.read_text()), yaml.safe_load(out.read_text())
    sim = raw["primitive"][0]
    assert sim["config"]["lidar_noise"] == {"noise_std": 0.03, "dropout_prob": 0.05}
    assert {k: v for k, v in sim["config"].items() if k != "lidar_noise"} == orig["primitive"][0]["config"]
    assert [e["config"] for e in raw["service"]] == [e["config"] for e in orig["service"]]
    env = {"RBNX_SIM_SCENE": "kitchen", "RBNX_SIM_RTF": "3", "RBNX_ATLAS_LISTEN": "127.0.0.1:0"}
    a, b = load_deploy(deploy, base_env=env), load_deploy(out, base_env=env)   # package paths still resolve
    assert [(e.name, e.root) for e in a.entries] == [(e.name, e.root) for e in b.entries]
    hal = next(e for e in b.entries if e.name == sim["name"])
    noise = parse_config(hal.config).lidar_noise
    assert (noise.noise_std, noise.dropout_prob) == (0.03, 0.05)


def test_variant_needs_a_simulator(tmp_path: Path) -> None:
    plain = tmp_path / "deploy.yaml"
    plain.write_text("manifestVersion: 1\nname: x\nservice: []\n")
    with pytest.raises(ValueError, match="no hal_panda_mobile primitive"):
        write_variant(plain, tmp_path / "out", {"lidar_noise": {"noise_std": 0.01, "dropout_prob": 0.0}})
