"""One real deployment for the abuse suite: ``rbnx boot`` of the HAL (small room), the mapping service and
navigation, with the maps root in the test's temp dir; helpers to find every provider's endpoints, to
check that no process died, and to prove that no file outside the maps root changed."""

from __future__ import annotations

import hashlib
import os
import subprocess
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import yaml
from support.boot import RbnxBoot
from support.procs import REPO, alive, wait_until

from robonix_api.atlas_client import AtlasClient
from robonix_api.types import LifecycleState, Transport

SCENE: dict[str, Any] = {
    "name": "abuse_room", "bounds": [0, 0, 6, 5],
    "walls": [{"start": a, "end": b, "thickness": 0.1, "height": 2.0}
              for a, b in (([0, 0], [6, 0]), ([6, 0], [6, 5]), ([6, 5], [0, 5]), ([0, 5], [0, 0]))],
    "boxes": [{"name": "crate", "center": [4.2, 1.2], "size": [0.6, 0.8], "height": 0.8}],
    "start": {"x": 1.5, "y": 1.5, "yaw": 0.0},
}
CONFIGS: dict[str, dict[str, Any]] = {
    "abuse_hal": {"scene": SCENE, "real_time_factor": 1.0, "odom_noise": "none"},
    "abuse_mapping": {"mode": "mapping", "use_sim_time": True},
    "abuse_nav": {"params_profile": "sim", "use_sim_time": True, "action_wait_s": 10},
}


def deploy_dict(maps_root: Path) -> dict[str, Any]:
    return {
        "manifestVersion": 1, "name": "abuse",
        "env": {"ROBONIX_HEARTBEAT_PERIOD_S": "2", "ROBONIX_NAV2_FORCE": "native",
                "ROBONIX_MAPS_ROOT": str(maps_root), "ROBONIX_MAP_DIR": ""},
        "system": {"atlas": {"listen": "${RBNX_ATLAS_LISTEN:-127.0.0.1:0}"}},
        "primitive": [{"name": "abuse_hal", "path": str(REPO / "hal_panda_mobile"), "config": CONFIGS["abuse_hal"]}],
        "service": [{"name": "abuse_mapping", "path": str(REPO / "slam_service"), "config": CONFIGS["abuse_mapping"]},
                    {"name": "abuse_nav", "path": str(REPO), "config": CONFIGS["abuse_nav"]}],
    }


def tree_digest(root: Path, skip: set[Path]) -> dict[str, str]:
    """path -> sha1 of every file under ``root`` (folders in ``skip`` left out), plus empty folders."""
    out: dict[str, str] = {}
    for dirpath, dirnames, filenames in os.walk(root):
        d = Path(dirpath)
        dirnames[:] = [n for n in dirnames if d / n not in skip]
        if not dirnames and not filenames:
            out[str(d)] = "<dir>"
        for name in filenames:
            p = d / name
            if p in skip:
                continue
            try:
                out[str(p)] = hashlib.sha1(p.read_bytes()).hexdigest()
            except OSError as exc:
                out[str(p)] = f"<{exc.strerror}>"
    return out


def git_status() -> str:
    return subprocess.run(["git", "status", "--porcelain", "--untracked-files=all"], cwd=REPO, capture_output=True,
                          text=True, timeout=60).stdout


@dataclass
class Deployment:
    boot: RbnxBoot
    tmp: Path
    maps_root: Path
    bait: Path
    atlas: str
    atlas_pid: int
    pids: dict[str, int]
    tried: dict[str, int] = field(default_factory=dict)
    _client: AtlasClient | None = None

    @property
    def client(self) -> AtlasClient:
        if self._client is None:
            self._client = AtlasClient(self.atlas)
        return self._client

    def count(self, what: str, n: int = 1) -> None:
        self.tried[what] = self.tried.get(what, 0) + n

    def endpoint(self, provider: str, contract_id: str, transport: str = "grpc") -> str:
        with self.client.connect_capability(consumer_id="abuse", provider_id=provider, contract_id=contract_id,
                                            transport=transport) as ch:
            return ch.endpoint

    def capabilities(self, transport: str) -> list[tuple[str, str]]:
        """(provider id, contract id) of every capability the deployment's providers declare on ``transport``."""
        out = []
        for prov in self.client.query():
            if prov.id not in self.pids:
                continue
            for cap in prov.capabilities:
                if cap.transport == Transport.parse(transport):
                    out.append((prov.id, cap.contract_id))
        return sorted(set(out))

    def assert_alive(self) -> None:
        dead = {name: pid for name, pid in {**self.pids, "atlas": self.atlas_pid}.items() if not alive(pid)}
        assert not dead, f"processes died: {dead}\n{self.boot.output()[-3000:]}"
        assert self.boot.proc.poll() is None, self.boot.output()[-3000:]

    def states(self) -> dict[str, LifecycleState]:
        return {p.id: p.state for p in self.client.query() if p.id in self.pids}


def boot_deployment(tmp: Path) -> Deployment:
    maps_root = tmp / "maps_root"
    maps_root.mkdir()
    bait = tmp / "bait"  # files outside the maps root that hostile map_dirs and ids aim at
    (bait / "sub").mkdir(parents=True)
    (bait / "map.yaml").write_text("image: map.pgm\nresolution: 0.05\norigin: [0, 0, 0]\n")
    (bait / "sub" / "keep.txt").write_text("must survive")
    path = tmp / "deploy.yaml"
    path.write_text(yaml.safe_dump(deploy_dict(maps_root), sort_keys=False))
    boot = RbnxBoot(path, tmp)
    boot.wait_ready(3, 240)
    st = boot.state()
    names = {c["name"]: c["pid"] for c in st["children"]}
    dep = Deployment(boot, tmp, maps_root, bait, st["atlas"], st["atlas_proc"]["pid"], names)
    wait_until(lambda: len(dep.capabilities("grpc")) >= 20, 120, "every provider's contracts declared", 0.5)
    return dep
