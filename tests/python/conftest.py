"""Shared fixtures: the `ekf` binary, the bundled real logs, and the bags `ekf` writes from them.

The binary is `$EKF_BIN` if set, else `target/debug/ekf`; the example `write_sample_bag` is
the one built beside it (`examples/` in the same folder). scripts/test-all.sh uses the ones
its `cargo test` stage built and sets EKF_BIN. The real logs live in `shared/data/` beside
the repository (CI clones `shared/` next to it); tests that need them are skipped, with the
reason, only when that folder is absent, and fail instead when `EKF_REQUIRE_DATA=1`.
"""

import json
import os
import subprocess
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]

MRPT_LOG = "2006-01ENE-21-SENA_Telecom_Faculty_one_loop_only.carmenlike.txt"
CARMEN_LOG = "aces-corrected.log.gz"


def find_shared_data():
    """The first `shared/data` folder at or above the repository root, or None."""
    for d in [ROOT, *ROOT.parents]:
        candidate = d / "shared" / "data"
        if candidate.is_dir():
            return candidate
    return None


@pytest.fixture(scope="session")
def ekf_bin():
    path = Path(os.environ.get("EKF_BIN") or ROOT / "target" / "debug" / "ekf")
    if not path.is_file():
        pytest.fail(
            f"ekf binary not found at {path}; build it with `cargo build -p ekf-cli --bins` "
            "or point EKF_BIN at it"
        )
    return path


@pytest.fixture(scope="session")
def sample_bag_writer(ekf_bin):
    """The example `write_sample_bag`, built with the `ekf` binary in use."""
    path = ekf_bin.parent / "examples" / "write_sample_bag"
    if not path.is_file():
        pytest.fail(
            f"example write_sample_bag not found at {path} (beside {ekf_bin}); build it with "
            "`cargo build -p ekf-cli --bins --examples`"
        )
    return path


@pytest.fixture(scope="session")
def shared_data():
    data = find_shared_data()
    if data is None or not (data / MRPT_LOG).is_file() or not (data / CARMEN_LOG).is_file():
        reason = (
            f"real logs absent: no shared/data/ with {MRPT_LOG} and {CARMEN_LOG} "
            f"at or above {ROOT} (CI clones shared/ beside the repository)"
        )
        if os.environ.get("EKF_REQUIRE_DATA") == "1":
            pytest.fail(reason + "; EKF_REQUIRE_DATA=1 makes this an error")
        pytest.skip(reason)
    return data


def run_ekf(ekf_bin, *args):
    """Runs `ekf ARGS --json` and returns its parsed JSON summary; fails on a non-zero exit."""
    cmd = [str(ekf_bin), *map(str, args), "--json"]
    proc = subprocess.run(cmd, cwd=ROOT, capture_output=True, text=True)
    if proc.returncode != 0:
        pytest.fail(f"{' '.join(cmd)} exited {proc.returncode}:\n{proc.stderr}")
    return json.loads(proc.stdout)


@pytest.fixture(scope="session")
def out_dir(tmp_path_factory):
    return tmp_path_factory.mktemp("ekf_outputs")


@pytest.fixture(scope="session")
def mrpt_import(ekf_bin, shared_data, out_dir):
    """`ekf import mrpt` of the Málaga log: (bag path, JSON summary)."""
    out = out_dir / "mrpt.mcap"
    summary = run_ekf(ekf_bin, "import", "mrpt", shared_data / MRPT_LOG, "--out", out)
    return out, summary


@pytest.fixture(scope="session")
def carmen_import(ekf_bin, shared_data, out_dir):
    """`ekf import carmen` of the ACES log with a 2° synthetic compass: (bag, JSON summary)."""
    out = out_dir / "aces.mcap"
    summary = run_ekf(
        ekf_bin, "import", "carmen", shared_data / CARMEN_LOG, "--out", out,
        "--synthetic-compass-deg", "2",
    )
    return out, summary


@pytest.fixture(scope="session")
def replay(ekf_bin, carmen_import, out_dir):
    """`ekf replay` of the imported ACES bag: (bag, TUM path, JSON summary)."""
    bag, _ = carmen_import
    out, tum = out_dir / "replay.mcap", out_dir / "replay.tum"
    summary = run_ekf(
        ekf_bin, "replay", bag, "--mode", "laser+compass", "--init-from-truth",
        "--out", out, "--tum", tum,
    )
    return out, tum, summary
