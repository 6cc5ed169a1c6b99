"""ROS 2 bags as users have them, written by a library we did not write (rosbags).

The bundled simulated run is rewritten by `rosbags` as a sqlite3 bag (its default storage,
what `ros2 bag record` writes on Humble and Foxy) and as an MCAP bag directory with
`metadata.yaml`; `ekf replay` gives the same summary and the same trajectory for both as
for the original `.mcap`. The bag directory `ekf replay --out DIR/` writes is read back by
rosbags' `AnyReader`, with the counts its metadata claims.
"""

from pathlib import Path

import pytest
from rosbags.highlevel import AnyReader
from rosbags.rosbag2 import StoragePlugin, Writer
from rosbags.typesys import Stores, get_typestore

from conftest import ROOT, run_ekf

SIM_BAG = ROOT / "testdata" / "sim-paper.mcap"


@pytest.fixture(scope="module")
def paper_config(ekf_bin, tmp_path_factory):
    """The simulated robot's settings (`ekf config --preset paper-robot`)."""
    import subprocess

    path = tmp_path_factory.mktemp("config") / "paper.toml"
    text = subprocess.run([str(ekf_bin), "config", "--preset", "paper-robot"], check=True,
                          capture_output=True, text=True).stdout
    path.write_text(text)
    return path


def rewrite(src, dst, storage):
    """Copies every message of `src` into a new rosbag2 bag at `dst`, raw bytes unchanged."""
    typestore = get_typestore(Stores.ROS2_HUMBLE)
    with AnyReader([src], default_typestore=typestore) as reader:
        with Writer(dst, version=9, storage_plugin=storage) as writer:
            conns = {}
            for conn, t_ns, raw in reader.messages():
                if conn.topic not in conns:
                    conns[conn.topic] = writer.add_connection(conn.topic, conn.msgtype,
                                                              typestore=typestore)
                writer.write(conns[conn.topic], t_ns, raw)
    return dst


def replay(ekf_bin, config, bag, tum):
    summary = run_ekf(ekf_bin, "replay", bag, "--config", config, "--init-from-truth",
                      "--tum", tum)
    return summary, tum.read_text()


@pytest.mark.parametrize("storage", [StoragePlugin.SQLITE3, StoragePlugin.MCAP])
def test_a_bag_written_by_rosbags_replays_like_the_mcap(storage, ekf_bin, paper_config,
                                                         tmp_path):
    bag = rewrite(SIM_BAG, tmp_path / "bag", storage)
    suffix = ".db3" if storage == StoragePlugin.SQLITE3 else ".mcap"
    assert [p.suffix for p in bag.iterdir() if p.name != "metadata.yaml"] == [suffix]
    expected, expected_tum = replay(ekf_bin, paper_config, SIM_BAG, tmp_path / "ref.tum")
    assert expected["accuracy"]["position_rmse_m"] < 0.02
    got, got_tum = replay(ekf_bin, paper_config, bag, tmp_path / "got.tum")
    assert got_tum == expected_tum
    for key in ("accuracy", "lines", "odometry", "headings"):
        assert got.get(key) == expected.get(key), key
    # The storage file alone (a .db3 passed by itself) is a bag too.
    storage_file = next(p for p in bag.iterdir() if p.suffix == suffix)
    alone, _ = replay(ekf_bin, paper_config, storage_file, tmp_path / "alone.tum")
    assert alone["accuracy"] == expected["accuracy"]
    # And so it is for the Python module.
    import ekf_loc

    result = ekf_loc.replay(str(bag), config=str(paper_config), init_from_truth=True)
    rows = [line.split() for line in expected_tum.splitlines() if not line.startswith("#")]
    assert result.x.tolist() == [float(r[1]) for r in rows]
    assert result.summary["accuracy"] == expected["accuracy"]


def test_the_bag_directory_ekf_writes_reads_back_with_rosbags(ekf_bin, paper_config, tmp_path):
    out = tmp_path / "replayed"
    summary = run_ekf(ekf_bin, "replay", SIM_BAG, "--config", paper_config, "--init-from-truth",
                      "--out", f"{out}/", "--tum", tmp_path / "est.tum")
    assert (out / "metadata.yaml").is_file() and (out / "replayed_0.mcap").is_file()
    typestore = get_typestore(Stores.ROS2_HUMBLE)
    with AnyReader([out], default_typestore=typestore) as reader:
        counts = {c.topic: c.msgcount for c in reader.connections}
        assert set(counts) >= {"/ekf/pose", "/ekf/markers", "/ekf/map", "/ekf/diagnostics"}
        got = {topic: 0 for topic in counts}
        poses = []
        for conn, t_ns, raw in reader.messages():
            got[conn.topic] += 1
            if conn.topic == "/ekf/pose":
                msg = reader.deserialize(raw, conn.msgtype)
                stamp = msg.header.stamp.sec * 10**9 + msg.header.stamp.nanosec
                assert stamp == t_ns
                poses.append((t_ns, msg.pose.pose.position.x, msg.pose.pose.position.y))
        assert got == counts, "metadata.yaml counts against the messages read"
        assert reader.message_count == sum(counts.values())
    tum = [line.split() for line in (tmp_path / "est.tum").read_text().splitlines()
           if line and not line.startswith("#")]
    # /ekf/pose carries the prediction and then the update at a scan's stamp; the TUM
    # file has the pose after everything fused at a stamp.
    last = list({t_ns: (t_ns, x, y) for t_ns, x, y in poses}.values())
    assert len(last) == len(tum)
    for (t_ns, x, y), row in zip(last, tum):
        assert abs(t_ns / 1e9 - float(row[0])) < 1e-6
        assert abs(x - float(row[1])) < 1e-6 and abs(y - float(row[2])) < 1e-6
    assert summary["accuracy"]["matched_poses"] > 0
