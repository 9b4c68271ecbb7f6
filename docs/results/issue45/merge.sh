#!/bin/sh
# Pool the two halves of run.sh (every search resumes from its checkpoint: nothing is simulated again but the
# reproduction check of every failure by simulate), then the hardest-20 suite of each method, every method on it.
set -e
OUT=${OUT:-out/issue45}
for m in colregs-vortex modified-vortex velocity-obstacle; do
  mkdir -p $OUT/$m
  cp $OUT/gradient/$m/search_gradient.json $OUT/cmaes_random/$m/search_cmaes.json \
     $OUT/cmaes_random/$m/search_random.json $OUT/$m/
  nice -n 10 .venv/bin/mmg-casadi falsify --method $m --env 5 --budget 1000 --objective collision --seed 0 \
    --figures distinct --out $OUT/$m
  nice -n 10 .venv/bin/mmg-casadi study hardest --methods colregs-vortex,modified-vortex,velocity-obstacle \
    --from $OUT/$m --k 20 --out $OUT/hardest_$m
done
