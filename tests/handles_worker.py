"""Helper of tests/test_handles.py, run as its own process (``python handles_worker.py COMMAND ARG``), so that a
crash in a compiled module (a broken cached .so) shows as an exit status, never as a dead test session.

    load DECLARATION.py   sewgen.load() it (the cache is SEWGEN_CACHE) after waiting for the file GO, if given
    files FILES.json      the mechanism of already generated files (JSON: name, files) through the build cache,
                          as load() does after deriving (no SymPy: the race is the cache's), after GO likewise
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
    go = os.environ.get("HANDLES_GO")
    while command in ("load", "files") and go and not os.path.exists(go):  # start the builds together
        time.sleep(0.002)
    if command == "load":
        mech = sewgen.load(arg)
    elif command == "files":
        from sewgen.engine.loader import _load_built, cache_root

        prebuilt = os.environ.get("HANDLES_PREBUILT")
        if prebuilt:  # the compiler replaced by a copy of a module built once, with a random delay: the race
            fake_compiler(prebuilt)  # is the cache's (lock, temporary folder, rename, marker), not gcc's

        with open(arg) as fh:
            spec = json.load(fh)
        mech = _load_built(cache_root(), spec["name"], spec["files"])
    elif command == "unpickle":
        with open(arg, "rb") as fh:
            mech = pickle.load(fh)
    else:
        raise SystemExit(f"unknown command {command!r}")
    if command == "files":  # SI numbers only: no quantity string, so no pint (a race trial stays short)
        mo = mech.solve(PHI, speed=100.0)
        print(json.dumps({"path": mech.build_info["path"], "cached": mech.build_info["cached"],
                          "obs": mo.obs.tobytes().hex(), "frc": ""}))
        return
    fa = mech.kinetostatics(PHI)
    print(json.dumps({"path": mech.build_info["path"], "cached": mech.build_info["cached"],
                      "obs": fa.motion.obs.tobytes().hex(), "frc": fa.frc.tobytes().hex()}))


def fake_compiler(prebuilt: str) -> None:
    """sewgen.engine.build.make_ffi replaced in this process: 'compiling' copies the module ``prebuilt``."""
    import random
    import shutil

    import sewgen.engine.build

    class Compiled:
        def compile(self, tmpdir):
            time.sleep(random.uniform(0.0, 0.05))
            dest = os.path.join(tmpdir, os.path.basename(prebuilt))
            with open(prebuilt, "rb") as src, open(dest, "wb") as out:  # written in pieces, like a linker
                while chunk := src.read(65536):
                    out.write(chunk)
                    time.sleep(0.001)
            shutil.copymode(prebuilt, dest)
            return dest

    sewgen.engine.build.make_ffi = lambda *args, **kwargs: Compiled()


if __name__ == "__main__":
    main(*sys.argv[1:3])
