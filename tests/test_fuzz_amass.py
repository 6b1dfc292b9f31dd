"""Hypothesis over AMASS ``.npz`` files: damaged bytes and arbitrary arrays.

Runs in a child process with a 3 GiB address-space cap (as the kernel crash tests do), so
that a decompression bomb or a crash fails the test instead of the machine. The only outcome
allowed is a trial or a :class:`~visprim.io.ReadError` naming the file.
"""

from __future__ import annotations

import os
import subprocess
import sys
import textwrap
from pathlib import Path

PYTHONPATH = str(Path(__file__).resolve().parents[1] / "python")
#: Examples per property (raise it for a longer run: VISPRIM_FUZZ_EXAMPLES=2000).
EXAMPLES = int(os.environ.get("VISPRIM_FUZZ_EXAMPLES", "100"))

CHILD = textwrap.dedent(
    """
    import io, resource, sys, tempfile, warnings, zipfile
    from pathlib import Path
    resource.setrlimit(resource.RLIMIT_AS, (3 << 30, 3 << 30))
    import numpy as np
    from hypothesis import given, settings, HealthCheck, strategies as st
    from visprim.io import ReadError, read
    from visprim.trial import Trial

    EXAMPLES = int(sys.argv[1])
    folder = Path(tempfile.mkdtemp())
    rng = np.random.default_rng(0)
    buf = io.BytesIO()
    np.savez(buf, poses=rng.normal(scale=0.3, size=(8, 156)), trans=np.zeros((8, 3)),
             mocap_framerate=np.array(120.0))
    STORED = buf.getvalue()
    buf = io.BytesIO()
    np.savez_compressed(buf, root_orient=rng.normal(size=(8, 3)), pose_body=np.zeros((8, 63)),
                        mocap_frame_rate=np.array(60.0), trans=np.zeros((8, 3)))
    DEFLATED = buf.getvalue()
    problems = []

    def outcome(path):
        try:
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                trial = read(path)
        except ReadError as exc:
            if not str(exc).startswith(str(path)):
                problems.append(f"ReadError not naming the file: {exc}")
            return
        except BaseException as exc:
            problems.append(f"{type(exc).__name__}: {exc}"[:300])
            return
        if not (isinstance(trial, Trial) and np.isfinite(trial.markers).all()):
            problems.append("a trial with non-finite markers")

    @settings(max_examples=EXAMPLES, deadline=None, suppress_health_check=list(HealthCheck))
    @given(base=st.sampled_from([STORED, DEFLATED]), data=st.data())
    def bytes_case(base, data):
        b = bytearray(base)
        for _ in range(data.draw(st.integers(1, 4))):
            pos = data.draw(st.integers(0, len(b)))
            how = data.draw(st.sampled_from(["insert", "replace", "delete", "cut", "flip"]))
            junk = data.draw(st.binary(min_size=1, max_size=8))
            if how == "insert":
                b[pos:pos] = junk
            elif how == "replace":
                b[pos : pos + len(junk)] = junk
            elif how == "delete":
                del b[pos : pos + len(junk)]
            elif how == "cut":
                del b[pos:]
            elif b:
                b[min(pos, len(b) - 1)] ^= 1 << data.draw(st.integers(0, 7))
        path = folder / "b_poses.npz"
        path.write_bytes(bytes(b))
        outcome(path)

    NAMES = ["poses", "root_orient", "pose_body", "trans", "joints", "Jtr", "betas",
             "mocap_framerate", "mocap_frame_rate", "other"]
    DTYPES = ["<f8", "<f4", "<i4", "|u1", "|b1", "<c16", "<U3", ">f8"]
    dims = st.lists(st.sampled_from([0, 1, 2, 3, 8, 22, 52, 63, 66, 156, 165]), max_size=3)

    @settings(max_examples=EXAMPLES, deadline=None, suppress_health_check=list(HealthCheck))
    @given(
        arrays=st.dictionaries(st.sampled_from(NAMES), st.tuples(dims, st.sampled_from(DTYPES),
                               st.sampled_from([0.0, 0.3, 1e300, float("nan"), -1.0, 1e-9])),
                               max_size=6),
        compressed=st.booleans(),
    )
    def array_case(arrays, compressed):
        made = {}
        for name, (shape, dtype, scale) in arrays.items():
            with np.errstate(all="ignore"):
                a = (rng.normal(size=shape) * scale)
                made[name] = a.astype(dtype) if dtype[1] != "U" else a.astype(str).astype(dtype)
        path = folder / "a_poses.npz"
        (np.savez_compressed if compressed else np.savez)(path, **made)
        outcome(path)

    bytes_case()
    array_case()
    print("PROBLEMS", len(problems))
    for p in problems[:20]:
        print(p)
    """
)


def test_amass_reader_fuzzed_in_a_capped_child() -> None:
    proc = subprocess.run(
        [sys.executable, "-c", CHILD, str(EXAMPLES)],
        capture_output=True,
        text=True,
        timeout=900,
        env={**os.environ, "PYTHONPATH": PYTHONPATH, "OPENBLAS_NUM_THREADS": "1"},
    )
    assert proc.returncode == 0, proc.stderr[-3000:]
    lines = proc.stdout.strip().splitlines()
    head = next(i for i, line in enumerate(lines) if line.startswith("PROBLEMS"))
    assert lines[head] == "PROBLEMS 0", "\n".join(lines[head:])
