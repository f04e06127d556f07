"""Run by scripts/wheel.sh --test in a new virtual environment that holds only the wheel and
numpy: imports stabint, steps a cloth, and checks which shared libraries the process loaded.
Every library the extension needs must come from the wheel (stabint.libs/) except the C and C++
runtimes, which manylinux lets a wheel take from the system, and the OpenCL ICD loader, which the
wheel leaves to the system on purpose (and whatever drivers the loader opens)."""
import os
import re
import sys
import sysconfig

import numpy as np


def libraries():
    return {line.split()[-1] for line in open("/proc/self/maps") if ".so" in line.split()[-1]}


before = libraries()  # the interpreter's and numpy's own
import stabint  # noqa: E402

assert stabint.__file__.startswith(sys.prefix), f"imported {stabint.__file__}, not the new environment's package"
sim = stabint.Simulator(stabint.cloth_grid(nx=12, ny=12, pinned=[0]))
x0 = sim.positions
for _ in range(10):
    sim.step()
assert np.isfinite(sim.positions).all() and sim.positions[-1, 1] < x0[-1, 1] - 1e-3

SYSTEM = re.compile(r"/(ld-linux[^/]*|lib(c|m|dl|pthread|rt|util|stdc\+\+|gcc_s|OpenCL)\.so[.\d]*)$")
loaded = libraries() - before
package = os.path.dirname(stabint.__file__)
ours = [p for p in loaded if p.startswith(package) or "/stabint.libs/" in p]
interpreter = sysconfig.get_path("stdlib")  # the standard library's own extension modules (json's)
foreign = sorted(p for p in loaded if p not in ours and not SYSTEM.search(p) and not p.startswith(interpreter))
assert not foreign, f"the wheel's extension loaded libraries from the system: {foreign}"
bundled = sorted(os.path.basename(p) for p in ours if "/stabint.libs/" in p)
assert any("cholmod" in b for b in bundled), bundled
print(f"wheel_check: imported from {package}, stepped a cloth; {len(bundled)} bundled libraries loaded "
      f"({', '.join(bundled)}), none from the system but the C/C++ runtimes and the OpenCL loader")

# OpenCL through the system's loader, after the check (the loader opens the machine's drivers,
# which are the system's by design): where a device exists, the wheel steps on it too.
devices = stabint.list_opencl_devices()
if devices:
    sim = stabint.Simulator(stabint.cloth_grid(nx=12, ny=12, pinned=[0]), stabint.SimulatorOptions(backend="OpenCL"))
    for _ in range(10):
        sim.step()
    assert np.isfinite(sim.positions).all()
    print(f"wheel_check: stepped on OpenCL ({devices[0].device_name})")
else:
    print("wheel_check: no OpenCL device on this machine; the CPU reference stepped")
