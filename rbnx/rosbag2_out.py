"""`rbnx record --format rosbag2`: the recording as a rosbag2 folder (``metadata.yaml`` + ``<name>_0.mcap``).

``ros2 bag play`` / ``ros2 bag info`` and rosbags' ``AnyReader`` open a bag through its ``metadata.yaml``
(rosbag2_bagfile_information, version 8: offered QoS as a YAML string, storage ``mcap``). The MCAP file is
the one :class:`rbnx.record.McapRecorder` writes; this layout adds the metadata file, rewritten atomically
after every periodic flush so a killed recorder still leaves a folder ``ros2 bag reindex`` can repair, and
on a clean stop the ``rosbag2`` metadata record rosbag2's own MCAP plugin writes into the file.
"""

from __future__ import annotations

import os
from pathlib import Path
from typing import TYPE_CHECKING, Any

import yaml

from rbnx.record import McapRecorder, qos_metadata

if TYPE_CHECKING:
    from rbnx.rosmsg import TopicSpec

METADATA_VERSION = 8  # the newest version whose offered_qos_profiles is the YAML string we already write


class BagExistsError(ValueError):
    """The bag folder exists already (``ros2 bag record`` refuses too); str() is one line."""


def bag_file(folder: Path) -> Path:
    """``run/`` -> ``run/run_0.mcap``, rosbag2's name for the first (here only) file of a bag."""
    return folder / f"{folder.name}_0.mcap"


def metadata(rec: McapRecorder, file_name: str) -> dict[str, Any]:
    """rosbag2_bagfile_information for what ``rec`` has written so far."""
    from rbnx.rosmsg import ros_name

    with rec._lock:
        counts = dict(rec.counts)
        start = rec.first_ns or 0
        duration = 0 if rec.first_ns is None or rec.last_ns is None else rec.last_ns - rec.first_ns
    total = sum(counts.values())
    topics = [{"topic_metadata": {"name": s.topic, "type": ros_name(s.msg_type), "serialization_format": "cdr",
                                  "offered_qos_profiles": qos_metadata(s.qos), "type_description_hash": ""},
               "message_count": counts[s.topic]} for s in rec.specs]
    return {"rosbag2_bagfile_information": {
        "version": METADATA_VERSION, "storage_identifier": "mcap", "relative_file_paths": [file_name],
        "duration": {"nanoseconds": duration}, "starting_time": {"nanoseconds_since_epoch": start},
        "message_count": total, "topics_with_message_count": topics,
        "compression_format": "", "compression_mode": "",
        "files": [{"path": file_name, "starting_time": {"nanoseconds_since_epoch": start},
                   "duration": {"nanoseconds": duration}, "message_count": total}],
        "custom_data": None, "ros_distro": "robonix-nav"}}


class Rosbag2Recorder(McapRecorder):
    """:class:`McapRecorder` writing into a new rosbag2 folder ``folder`` and keeping its metadata.yaml."""

    def __init__(self, folder: str | Path, specs: list[TopicSpec] | tuple[TopicSpec, ...],
                 domain_id: int | None = None, **kwargs: Any) -> None:
        self.folder = Path(folder)
        if self.folder.exists():
            raise BagExistsError(f"{self.folder}: exists already; give a new folder name")
        super().__init__(bag_file(self.folder), specs, domain_id, **kwargs)

    def start(self) -> None:
        self.folder.mkdir()
        super().start()
        self._write_metadata()

    def flushed(self) -> None:
        self._write_metadata()

    def before_finish(self, writer: Any) -> None:
        info = metadata(self, bag_file(self.folder).name)["rosbag2_bagfile_information"]
        writer.add_metadata("rosbag2", {"serialized_metadata": yaml.safe_dump(info, sort_keys=False)})

    def stop(self) -> None:
        super().stop()
        if self.folder.is_dir():
            self._write_metadata()

    def _write_metadata(self) -> None:
        """metadata.yaml through a temporary file and a rename, so a reader never sees half of it."""
        path = self.folder / "metadata.yaml"
        tmp = path.with_suffix(".yaml.tmp")
        tmp.write_text(yaml.safe_dump(metadata(self, bag_file(self.folder).name), sort_keys=False))
        os.replace(tmp, path)
