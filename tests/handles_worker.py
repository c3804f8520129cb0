"""Helper of tests/test_handles.py, run as its own process (``python handles_worker.py COMMAND ARG``), so that a
crash in a compiled module (a broken cached .so) shows as an exit status, never as a dead test session.

    load DECLARATION.py   sewgen.load() it (the cache is SEWGEN_CACHE) after waiting for the file GO, if given
    unpickle BLOB         pickle.load() a Mechanism from BLOB

Either way the mechanism then solves a fixed sweep; the last line of stdout is JSON: the shared object's path,
whether it came from the cache, and the sweep's arrays as hex (so the parent compares them bit for bit).
"""
from __future__ import annotations

import json
import os
import pickle
import sys
import time

import numpy as np

import sewgen

PHI = np.radians(np.arange(0.0, 360.0, 10.0))


def main(command: str, arg: str) -> None:
    if command == "load":
        go = os.environ.get("HANDLES_GO")
        while go and not os.path.exists(go):  # start the builds together
            time.sleep(0.005)
        mech = sewgen.load(arg)
    elif command == "unpickle":
        with open(arg, "rb") as fh:
            mech = pickle.load(fh)
    else:
        raise SystemExit(f"unknown command {command!r}")
    fa = mech.kinetostatics(PHI)
    print(json.dumps({"path": mech.build_info["path"], "cached": mech.build_info["cached"],
                      "obs": fa.motion.obs.tobytes().hex(), "frc": fa.frc.tobytes().hex()}))


if __name__ == "__main__":
    main(*sys.argv[1:3])
