#!/bin/sh
# Pool the searches of one method run by run.sh (every search resumes from its checkpoint: nothing is simulated
# again but the reproduction of every failure by simulate), then its hardest-20 suite with every method on it.
#   sh merge.sh METHOD [SEARCHES]      (SEARCHES default gradient,cmaes,random)
set -e
OUT=${OUT:-out/issue45}
m=$1
searches=${2:-gradient,cmaes,random}
mkdir -p $OUT/$m
for s in $(echo $searches | tr , ' '); do
  if [ $s = gradient ]; then cp $OUT/gradient/$m/search_gradient.json $OUT/$m/
  else cp $OUT/cmaes_random/$m/search_$s.json $OUT/$m/; fi
done
nice -n 10 .venv/bin/mmg-casadi falsify --method $m --env 5 --budget 1000 --objective collision --seed 0 \
  --search $searches --figures distinct --out $OUT/$m
nice -n 10 .venv/bin/mmg-casadi study hardest --methods colregs-vortex,modified-vortex,velocity-obstacle \
  --from $OUT/$m --k 20 --out $OUT/hardest_$m
