#!/bin/sh
# bench/step_passes.sh BUILD_DIR METHOD: N_Vector operations that pass over the data, per step
# (callgrind's call counts of N_V*_Serial other than the accessors; difference of two runs), for
# the fused kernel (ceode: 0, the update is one pass of its own) and the generic path.
bin=$1/bench/bench_step
shift
out=$(mktemp)
calls() {
  valgrind --tool=callgrind --callgrind-out-file=$out "$bin" --count "$@" >/dev/null 2>&1
  CG=$out python3 - <<'PY'
import os, re
cur=None; total=0
names={}
for line in open(os.environ['CG']):
    m0=re.match(r'^fn=\((\d+)\) (.*)', line)
    if m0: names[m0.group(1)]=m0.group(2)
    m=re.match(r'^cfn=\((\d+)\)(?: (.*))?', line)
    if m:
        if m.group(2): names[m.group(1)]=m.group(2)
        cur=names.get(m.group(1),'')
        continue
    m=re.match(r'^calls=(\d+)', line)
    if m and cur and re.search(r'N_V\w*_Serial', cur) and not re.search(r'GetArrayPointer|GetLength|GetVectorID|Clone|Destroy|New|Make|Space|GetCommunicator', cur):
        total+=int(m.group(1))
print(total)
PY
}
for v in ceode ceode_generic; do
  a=$(calls $v "$1" 1000 100); b=$(calls $v "$1" 1000 200)
  echo "$1 $v: $(( (b - a) / 100 )) N_Vector data operations per step"
done
