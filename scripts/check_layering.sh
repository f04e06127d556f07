#!/usr/bin/env bash
# The layering rule (docs/development.md, "Layering"): the element math, the scene, the solver,
# the backends, contact resolution and the integrators' formulas sit below the stepping driver (contact/ there so that the
# driver can hold a ContactResolver). They take the library's shared types from the leaf
# header stabint/types.hpp and include neither the stepping facade (stabint/simulator.hpp,
# batch.hpp, events.hpp, stabint.hpp) nor any header of the driver's rooms (host/driver/,
# state/, scripting/). Fails, naming the file
# and line, on an include that breaks it.
set -euo pipefail
cd "$(dirname "$0")/.."

lower=(host/elements host/scene host/solver host/contact host/cpu host/opencl host/opencl_disabled host/backend host/integrator)
if violations=$(grep -rnE '#include *[<"](stabint/(simulator|batch|events|stabint)\.hpp|(driver|state|scripting)/)' "${lower[@]}"); then
  echo "$violations" >&2
  echo "layering: the lines above include the stepping layer from below it (docs/development.md, \"Layering\")" >&2
  exit 1
fi
if violations=$(grep -rnE '#include *"scene/' host/elements); then
  echo "$violations" >&2
  echo "layering: host/elements reads a running scene through RunningScene, never scene/ (docs/development.md, \"Layering\")" >&2
  exit 1
fi
# The floors (docs/architecture.md): every include of a host file names a room on its own floor or
# below. A room not listed here, or a file loose at the top of host/, fails too, so a new one
# gets its floor when it is made.
/usr/bin/env python3 - <<'PY'
import os, re, sys

FLOORS = [
    ["common"],
    ["elements"],
    ["scene"],
    ["io", "backend"],
    ["cpu", "opencl", "opencl_disabled", "solver"],
    ["contact", "integrator"],
    ["state"],
    ["driver", "scripting", "reporting"],
    ["c_api"],
]
floor = {room: i for i, rooms in enumerate(FLOORS) for room in rooms}
bad = []
for root, _, files in os.walk("host"):
    for name in files:
        if not name.endswith((".cpp", ".hpp", ".h")):
            continue
        path = os.path.join(root, name)
        parts = path.split(os.sep)
        room = parts[1]
        if room not in floor:
            bad.append(f"{path}: room '{room}' has no floor in scripts/check_layering.sh")
            continue
        for number, line in enumerate(open(path), 1):
            m = re.match(r'\s*#include\s+"([^"]+)"', line)
            if not m:
                continue
            target = m.group(1).split("/")[0]
            if "/" not in m.group(1) and os.path.exists(os.path.join(root, m.group(1))):
                target = room  # its own room's file, by a relative name
            if target not in floor:
                continue  # a header outside host/ (kernels' generated sources, ...)
            if floor[target] > floor[room]:
                bad.append(f"{path}:{number}: {room} (floor {floor[room]}) includes {m.group(1)} "
                           f"(floor {floor[target]}), a floor above it")
if bad:
    print("\n".join(bad), file=sys.stderr)
    print("layering: the lines above break the floors (docs/architecture.md)", file=sys.stderr)
    sys.exit(1)
print(f"layering: ok ({sum(map(len, FLOORS))} rooms on {len(FLOORS)} floors)")
PY
echo "layering: ok (${lower[*]} include neither the facade nor the driver's rooms)"
