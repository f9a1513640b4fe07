"""The map store's file boundary, on real files: map_dir confined to the maps root (symlinks resolved),
full-string map ids, only marked folders replaced or deleted, notes capped, saves of one id serialized,
and staging folders of killed saves cleaned at start (a real child process SIGKILLed mid-save)."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import threading
from pathlib import Path

import numpy as np
import pytest
from support.procs import wait_until

from robonix_api.mapfile import load_map_yaml
from robonix_common.grid import GridMap
from slam_service.map_paths import MARKER, MapDirError, MapIdError, check_id, resolve_map_dir
from slam_service.maps import MapStore, MapStoreError

LOCK = ".robonix-maps.lock"


def _grid(v: int = 0, n: int = 40) -> GridMap:
    data = np.full((n, n), -1, dtype=np.int8)
    data[5:-5, 5:-5] = v
    return GridMap(data, 0.05, -1.0, -0.5)


@pytest.fixture
def root(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> Path:
    r = tmp_path / "root"
    r.mkdir()
    monkeypatch.setenv("ROBONIX_MAPS_ROOT", str(r))
    return r


def _snapshot(folder: Path) -> dict[str, bytes]:
    return {str(p.relative_to(folder)): p.read_bytes() for p in sorted(folder.rglob("*")) if p.is_file()}


def test_map_dir_must_resolve_under_the_maps_root(root: Path, tmp_path: Path) -> None:
    outside = tmp_path / "outside"
    outside.mkdir()
    (root / "escape").symlink_to(outside, target_is_directory=True)
    for bad in (str(outside), "../outside", str(root / ".." / "outside"), "escape", str(root / "escape" / "sub"),
                "/etc", "~/"):
        with pytest.raises(MapDirError, match="^map_dir: .*outside the maps root"):
            MapStore(bad)
    assert resolve_map_dir("site_a") == root.resolve() / "site_a"  # relative: inside the root
    assert MapStore(str(root / "b")).root == root.resolve() / "b"
    assert MapStore(str(root)).root == root.resolve()
    assert list(outside.iterdir()) == []  # nothing written through the symlink


def test_map_ids_match_the_whole_string_and_errors_stay_short() -> None:
    for bad in ("ok\n", "ok\r", "\nok", "a\x00b", "é", "x" * 65):
        with pytest.raises(MapIdError, match="^map_id: "):
            check_id(bad)
    with pytest.raises(MapIdError) as info:
        check_id("y" * 1_000_000)
    assert len(str(info.value)) < 400
    assert "1000000 chars" in str(info.value)
    assert check_id("a" * 64) == "a" * 64


def test_delete_refuses_a_folder_the_store_did_not_write(root: Path) -> None:
    store = MapStore(str(root))
    keep = root / "precious"
    (keep / "sub").mkdir(parents=True)
    (keep / "sub" / "data.txt").write_text("not a map")
    (keep / "map.yaml").write_text("image: x.pgm\n")  # even a map.yaml is not enough: the marker is
    before = _snapshot(keep)
    with pytest.raises(MapStoreError, match=f"no {MARKER} marker"):
        store.delete("precious")
    with pytest.raises(MapStoreError, match=f"no {MARKER} marker"):  # nor replaced by a save of that id
        store.save("precious", _grid(), None, "")
    assert _snapshot(keep) == before

    target = root.parent / "victim"
    target.mkdir()
    (target / MARKER).write_text("forged marker")
    (target / "file").write_text("x")
    (root / "link").symlink_to(target, target_is_directory=True)
    with pytest.raises(MapStoreError, match="marker"):
        store.delete("link")
    assert (target / "file").read_text() == "x"

    store.save("real", _grid(), None, "mine")
    assert (root / "real" / MARKER).is_file()
    store.delete("real")
    assert not (root / "real").exists()


def test_oversized_note_is_refused_and_listing_is_capped(root: Path) -> None:
    store = MapStore(str(root))
    with pytest.raises(MapStoreError, match="^note: at most 4096 bytes, got 3900000"):
        store.save("big", _grid(), None, "n" * 3_900_000)
    assert not (root / "big").exists()
    store.save("ok", _grid(), None, "é" * 2048)  # 4096 bytes exactly
    legacy = root / "legacy"  # a map written before the cap, with a huge note in meta.json
    legacy.mkdir()
    (legacy / "meta.json").write_text('{"note": "' + "z" * 3_900_000 + '", "created": 1}')
    listed = store.list()
    assert {m["map_id"] for m in listed} == {"ok", "legacy"}
    assert all(len(m["note"]) <= 4096 for m in listed)


def test_concurrent_saves_of_one_id_leave_one_whole_map_and_no_staging(root: Path) -> None:
    store = MapStore(str(root))
    errors: list[BaseException] = []

    def saver(v: int) -> None:
        try:
            for _ in range(4):
                store.save("same", _grid(v), None, f"writer {v}")
        except BaseException as exc:
            errors.append(exc)

    threads = [threading.Thread(target=saver, args=(v,)) for v in (0, 100, 0, 100, 0, 100)]
    for t in threads:
        t.start()
    for t in threads:
        t.join(120)
    assert not errors, errors
    assert sorted(p.name for p in root.iterdir()) == [LOCK, "same"]
    grid = load_map_yaml(root / "same" / "map.yaml")
    assert np.count_nonzero(grid.data == 0) in (0, 900)
    assert np.count_nonzero(grid.data == 100) in (0, 900)


_SAVER = """
import sys, numpy as np
from robonix_common.grid import GridMap
from slam_service.maps import MapStore
store = MapStore(sys.argv[1])
grid = GridMap(np.zeros((400, 400), dtype=np.int8), 0.05, 0.0, 0.0)
def slow_session(path):
    np.savez(path, big=np.zeros(2_000_000))
while True:
    store.save("m", grid, slow_session, "loop")
"""


def test_staging_of_killed_saves_is_cleaned_at_start(root: Path) -> None:
    MapStore(str(root)).save("m", _grid(), None, "before the kills")
    stale = []
    for _ in range(6):
        proc = subprocess.Popen([sys.executable, "-c", _SAVER, str(root)], stdin=subprocess.DEVNULL)
        try:
            wait_until(lambda: any(".saving-" in p.name or ".old-" in p.name for p in root.iterdir()), 60,
                       "a save in progress")
        finally:
            os.kill(proc.pid, signal.SIGKILL)
            proc.wait(30)
        stale += [p.name for p in root.iterdir() if p.name.startswith(".m.")]
    assert stale, "no staging folder was ever caught"
    store = MapStore(str(root))  # start: the leftovers of the dead writers go
    assert store.cleaned >= 1
    assert sorted(p.name for p in root.iterdir()) == [LOCK, "m"]
    assert load_map_yaml(root / "m" / "map.yaml").width in (40, 400)  # the old map or a whole new one


def test_an_interrupted_swap_gets_its_old_map_back(root: Path) -> None:
    store = MapStore(str(root))
    store.save("m", _grid(100), None, "previous")
    dead = 2**22 + 12345  # above the default pid_max: no such process
    os.rename(root / "m", root / f".m.old-{dead}-1")
    (root / f".m.saving-{dead}-x").mkdir()
    (root / f".other.saving-{os.getpid()}-y").mkdir()  # a save of this live process: left alone
    MapStore(str(root))
    assert sorted(p.name for p in root.iterdir()) == sorted([LOCK, "m", f".other.saving-{os.getpid()}-y"])
    assert store.list()[0]["note"] == "previous"
