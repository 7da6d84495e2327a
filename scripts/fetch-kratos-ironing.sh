#!/usr/bin/env bash
# Fetch the input files of Kratos' shallow_ironing_3D validation case (KratosMultiphysics/Examples,
# BSD licence, author V. Mataix Ferrandiz) at a pinned commit into build/kratos-ironing/: the
# hexahedral mesh our meshes/shallow_ironing*.msh were converted from, the parameter files
# benchmarks/peers/kratos_ironing.py runs, and the figures the reference values of
# benchmarks/ironing.py were read from. Benchmarks only; nothing in make test needs them.
set -euo pipefail
commit=9eacc7b3dce247411b77180c54477f5d83daa159
base=https://raw.githubusercontent.com/KratosMultiphysics/Examples/$commit/contact_structural_mechanics/validation/shallow_ironing_3D
out=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)/build/kratos-ironing
mkdir -p "$out/source"
for f in source/shallow_ironing3D.mdpa source/ProjectParameters_literature.json source/ProjectParameters_frictional.json \
         source/StructuralMaterials.json data/setup.png data/solution_frictionless.png data/solution_frictional.png; do
    target="$out/$(basename "$f")"
    [ "${f#source/}" != "$f" ] && [ "$(basename "$f")" != shallow_ironing3D.mdpa ] && target="$out/source/$(basename "$f")"
    [ -s "$target" ] || curl -fsSL "$base/$f" -o "$target"
done
echo "fetch-kratos-ironing: $out"
