#!/usr/bin/env bash
# The layering rule (docs/development.md, "Layering"): the element math, the scene, the solver,
# the backends and contact resolution sit below the stepping driver (contact/ there so that the
# driver can hold a ContactResolver). They take the library's shared types from the leaf
# header stabint/types.hpp and include neither the stepping facade (stabint/simulator.hpp,
# batch.hpp, events.hpp, stabint.hpp) nor any header of the driver's rooms (host/integrator/,
# state/, scripting/). Fails, naming the file
# and line, on an include that breaks it.
set -euo pipefail
cd "$(dirname "$0")/.."

lower=(host/elements host/scene host/solver host/contact host/cpu host/opencl host/opencl_disabled host/backend.hpp host/device_profiles.hpp
       host/device_profiles.cpp host/kernel_constants.hpp host/kernel_constants.cpp)
if violations=$(grep -rnE '#include *[<"](stabint/(simulator|batch|events|stabint)\.hpp|(integrator|state|scripting)/)' "${lower[@]}"); then
  echo "$violations" >&2
  echo "layering: the lines above include the stepping layer from below it (docs/development.md, \"Layering\")" >&2
  exit 1
fi
if violations=$(grep -rnE '#include *"scene/' host/elements); then
  echo "$violations" >&2
  echo "layering: host/elements reads a running scene through RunningScene, never scene/ (docs/development.md, \"Layering\")" >&2
  exit 1
fi
echo "layering: ok (${lower[*]} include neither the facade nor the driver's rooms)"
