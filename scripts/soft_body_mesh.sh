#!/usr/bin/env bash
# Meshes the main job's soft body (issue 23): CGAL's elephant surface, which Debian's
# libcgal-demo ships in /usr/share/doc/libcgal-demo/data.tar.gz (CGAL 5.5.1's data/meshes/
# elephant.off, 2,775 vertices, 5,558 triangles; files of CGAL without their own notice are
# CC0 1.0, /usr/share/doc/libcgal-demo/copyright), tetrahedralized by TetGen (Debian's tetgen).
# Nothing is downloaded: both packages come from scripts/install-deps.sh.
#
# Usage: scripts/soft_body_mesh.sh [OUT_DIR]   (default results/mesh)
# Writes OUT_DIR/elephant.off and TetGen's OUT_DIR/elephant.1.node, elephant.1.ele (and .face,
# .edge). TetGen is deterministic, so a rerun writes the same files (idempotent).
#   -p   mesh the inside of the closed surface (a piecewise linear complex)
#   -Y   keep the surface as it is (no Steiner points on it), so the rendered skin is CGAL's
#   -q2  radius-edge ratio <= 2 inside: no slivers, and about 200 interior points, so the body
#        stays at ~3k vertices, small enough for real time at h = 1/30 with 10 iterations
#   -Q   quiet
set -euo pipefail
cd "$(dirname "$0")/.."
out="${1:-results/mesh}"
archive=/usr/share/doc/libcgal-demo/data.tar.gz
if [ ! -f "$archive" ]; then
  echo "soft_body_mesh: $archive missing (Debian package libcgal-demo; scripts/install-deps.sh)" >&2
  exit 1
fi
mkdir -p "$out"
tar -xzf "$archive" -O data/meshes/elephant.off > "$out/elephant.off"
rm -f "$out"/elephant.1.*
tetgen -pYq2 -Q "$out/elephant.off"
echo "soft_body_mesh: $out/elephant.1.node: $(head -n1 "$out/elephant.1.node" | awk '{print $1}') vertices," \
  "$(head -n1 "$out/elephant.1.ele" | awk '{print $1}') tets (TetGen -pYq2 of CGAL's elephant.off)"
