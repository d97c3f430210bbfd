"""Where the result file's memory growth comes from (the scale target's peak memory).

Writes 16 columns at 4 samples per revolution through ``results.ResultWriter`` (blocks of 16384
rows of smooth data, no integration) and prints the process's resident memory and HDF5's
metadata cache size (``H5Fget_mdc_size``: max, min clean, current, entries) at 10³, 2×10⁵,
5×10⁵ and 10⁶ revolutions, in one of five variants: ``default`` (the file in HDF5's 1.10
format, ``results.FILE_FORMAT``); ``v108``, the file in h5py's default bounds, the 1.8 format,
whose chunk index is a B-tree; ``cap``, the metadata cache held at 2 MiB (its default starts
there and may grow to 32 MiB); ``limits``, HDF5's free lists limited to 1 MiB in all and 256 KiB
per list (``H5set_free_list_limits``); ``gc``, HDF5's free lists emptied at each checkpoint
(``H5garbage_collect``). The last two call the libhdf5 that h5py bundles through ctypes (h5py
does not wrap them).

Rerun: ``for v in default v108 cap limits gc; do .venv/bin/python
tools/hdf5_memory_growth.py $v; done`` (each writes /tmp/hdf5_memory_growth_<variant>.h5).
"""
import ctypes
import glob
import os
import sys
import time
from pathlib import Path

import h5py
import numpy as np

from transient import results
from transient.results import ResultWriter

VARIANTS = ("default", "v108", "cap", "limits", "gc")
ROWS_PER_REV = 4
BLOCK = 16384


def rss_mb() -> float:
    with open("/proc/self/status") as status:
        for line in status:
            if line.startswith("VmRSS"):
                return int(line.split()[1]) / 1024
    return float("nan")


def main(variant: str) -> None:
    libs = os.path.join(os.path.dirname(h5py.__file__), os.pardir, "h5py.libs", "libhdf5-*.so*")
    lib = ctypes.CDLL(glob.glob(libs)[0])  # the copy h5py has loaded already
    if variant == "limits" and lib.H5set_free_list_limits(*(1 << 20, 1 << 18) * 3) < 0:
        sys.exit("H5set_free_list_limits failed")
    if variant == "v108":
        results.FILE_FORMAT = None  # h5py's default bounds
    columns = {f"c{i}": "-" for i in range(16)}
    path = Path(f"/tmp/hdf5_memory_growth_{variant}.h5")
    writer = ResultWriter(path, "growth", "", columns, force=True)
    if variant == "cap":
        config = writer.f.id.get_mdc_config()
        config.set_initial_size, config.initial_size = True, 1 << 21
        config.min_size, config.max_size = 1 << 20, 1 << 21
        writer.f.id.set_mdc_config(config)
    rows = np.arange(BLOCK, dtype=float)
    done, t0 = 0, time.perf_counter()
    for revolutions in (1e3, 2e5, 5e5, 1e6):
        while done < revolutions * ROWS_PER_REV:
            x = np.sin((rows + done) * 1e-3)
            writer.append({name: x + i for i, name in enumerate(columns)})
            done += BLOCK
        if variant == "gc" and lib.H5garbage_collect() < 0:
            sys.exit("H5garbage_collect failed")
        print(f"{variant}: {revolutions:.0e} revolutions: RSS {rss_mb():.1f} MB, metadata cache "
              f"{writer.f.id.get_mdc_size()}, {time.perf_counter() - t0:.1f} s", flush=True)
    writer.f.close()
    path.with_name(f".{path.name}.part").unlink(missing_ok=True)


if __name__ == "__main__":
    if len(sys.argv) != 2 or sys.argv[1] not in VARIANTS:
        sys.exit(f"usage: hdf5_memory_growth.py {{{'|'.join(VARIANTS)}}}")
    main(sys.argv[1])
