"""The Q4 cantilever plate of bench/fe_plate_model.h, the very arrays the C scenes use.

bench/fe_plate_c_scene (bench/python/fe_plate_c_scene.cpp) writes the C assembly: K in CSR,
the row-sum lumped masses, the start of wp_fe_plate's scaling scene and a probe p with K p;
`load` reads them into scipy.sparse / numpy and checks that scipy's product K p reproduces the
C product to round-off, so the matrix numpy holds is the one the C scene integrates.
"""
import os
import subprocess
import tempfile

import numpy as np
import scipy.sparse as sp

MAGIC = b"CEFEPLT1"


class Plate:
    def __init__(self, K, mass, x0):
        self.K, self.mass, self.x0 = K, mass, x0
        self.n = K.shape[0]


def read(path):
    """Plate from an export file; raises ValueError when the file or the check is wrong."""
    with open(path, "rb") as f:
        if f.read(8) != MAGIC:
            raise ValueError(f"{path}: not a fe_plate_c_scene export")
        n, nnz = (int(v) for v in np.fromfile(f, np.int64, 2))
        rowptr = np.fromfile(f, np.int32, n + 1)
        col = np.fromfile(f, np.int32, nnz)
        val = np.fromfile(f, np.float64, nnz)
        mass, x0, probe, kprobe = (np.fromfile(f, np.float64, n) for _ in range(4))
    if len(kprobe) != n or rowptr[-1] != nnz:
        raise ValueError(f"{path}: truncated")
    K = sp.csr_matrix((val, col, rowptr), shape=(n, n))
    # Each row's sum has at most 18 terms of either sign: the bound is 18 ulps of sum |K| |p|.
    scale = abs(K) @ np.abs(probe)
    if np.any(np.abs(K @ probe - kprobe) > 18 * np.finfo(float).eps * scale):
        raise ValueError(f"{path}: scipy's K p differs from the C product beyond round-off")
    return Plate(K, mass, x0)


def load(c_scene, nx, ny):
    """Exports the nx x ny plate with the C program and reads it."""
    with tempfile.TemporaryDirectory() as d:
        path = os.path.join(d, "plate.bin")
        subprocess.run([c_scene, "export", str(nx), str(ny), path], check=True,
                       stdout=subprocess.DEVNULL)
        return read(path)


def c_run(c_scene, nx, ny, method, h, steps):
    """(t, x, v) after `steps` CE_ONE_STEP steps of the C API run (fe_plate_c_scene run)."""
    with tempfile.TemporaryDirectory() as d:
        path = os.path.join(d, "run.bin")
        subprocess.run([c_scene, "run", str(nx), str(ny), method, repr(h), str(steps), path],
                       check=True, stdout=subprocess.DEVNULL)
        data = np.fromfile(path, np.float64)
    n = (len(data) - 1) // 2
    return data[0], data[1:n + 1], data[n + 1:]


def c_time(c_scene, nx, ny, method, h, chunk, reps):
    """(seconds per step of each timed chunk, the C guard's stable step at safety 1)."""
    out = subprocess.run([c_scene, "time", str(nx), str(ny), method, repr(h), str(chunk),
                          str(reps)], check=True, capture_output=True, text=True).stdout
    per_step, stable = [], float("nan")
    for ln in out.splitlines():
        w = ln.split()
        if w[0] == "chunk":
            per_step.append(float(w[2]))
        elif w[0] == "stable_step":
            stable = float(w[1])
    return per_step, stable
