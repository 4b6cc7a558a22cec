#!/usr/bin/env bash
# Issue 28 acceptance check: every listed hostile experiment file is refused by
# `run --dry-run` with exit 2 and one line, quickly and in bounded memory; the abort /
# hang / runaway cases finish or refuse within their budget. Prints a table.
# Usage: scripts/check_hostile.sh [path/to/reconbench]   (default target/release/reconbench)
set -u
BIN=$(realpath "${1:-target/release/reconbench}")
W=$(mktemp -d /tmp/h28-check.XXXXXX)
trap 'rm -rf "$W"' EXIT
cd "$W"
FAIL=0
printf '| case | exit | time s | max RSS MB | message (first 80 chars) |\n|---|---|---|---|---|\n'

# run NAME WANT_EXIT MAX_SECONDS CMD...: one table row; WANT_EXIT "0|2" allows either.
run() {
    local name=$1 want=$2 max_s=$3
    shift 3
    /usr/bin/time -f '%e %M' -o "$W/time" timeout -s KILL 120 "$@" >"$W/out" 2>"$W/err"
    local code=$?
    read -r secs rss_kb < <(tail -1 "$W/time") || { secs=?; rss_kb=0; }
    [[ "$rss_kb" =~ ^[0-9]+$ ]] || rss_kb=0
    local rss=$((rss_kb / 1024))
    local lines msg
    lines=$(grep -v '^Command exited\|^Command terminated' "$W/err" | wc -l)
    msg=$(grep -v '^Command exited\|^Command terminated' "$W/err" | head -1 | cut -c1-80 | tr '|' '/')
    [ -z "$msg" ] && msg="(stdout) $(tail -1 "$W/out" | cut -c1-70 | tr '|' '/')"
    local ok=1
    [[ "|$want|" == *"|$code|"* ]] || ok=0
    [ "$rss" -lt 1024 ] || ok=0
    awk -v s="$secs" -v m="$max_s" 'BEGIN{exit !(s+0 <= m+0)}' || ok=0
    if [ "$code" = 2 ] && [ "$lines" -ne 1 ]; then ok=0; msg="$lines lines: $msg"; fi
    [ $ok = 1 ] || { FAIL=1; name="**FAIL** $name"; }
    printf '| %s | %s | %s | %s | %s |\n' "$name" "$code" "$secs" "$rss" "$msg"
}

base='seed = 1
seeds = 1
'
data='[[datasets]]
name = "s"
shape = "sphere"
points = 200
'
meth='[[methods]]
name = "pf"
'
exp() { printf '%s' "$2" >"$W/$1.toml"; run "dry-run $1" 2 1 "$BIN" run --dry-run "$W/$1.toml"; }

exp points_neg "$base${data/points = 200/points = -100}$meth"
exp points_1e12 "$base${data/points = 200/points = 1000000000000}$meth"
exp points_i64max "$base${data/points = 200/points = 9223372036854775807}$meth"
exp grid_1e6 "$base${data/points = 200/points = 200
sampler = \"grid:nu=1000000,nv=1000000\"}$meth"
exp duplicate_1e9 "$base$data[[perturbations]]
duplicate = 1e9
$meth"
exp min_samples_1e11 "$base$data$meth[metrics.mesh.distance]
min_samples = 100000000000
"
exp k_1e12 "$base$data[[methods]]
name = \"pf\"
params = { k = 1000000000000 }
"
exp timeout_1e300 "${base}timeout = 1e300
$data$meth"
exp memory_0 "${base}memory_limit_mib = 0
$data$meth"
exp seeds_1e7 "seed = 1
seeds = 10000000
$data$meth"
exp name_dotdot "name = \"..\"
$base$data$meth"
exp name_dot "name = \".\"
$base$data$meth"
exp name_long "name = \"$(printf 'a%.0s' $(seq 300))\"
$base$data$meth"
exp metrics_key "$base$data$meth[metrics.mesh]
bogus_key = 1
"
exp report_metric "$base$data$meth[report]
metrics = [\"chamfer_l7\"]
"
exp expect_where "$base$data$meth[[expect]]
where = { methd = \"pf\" }
metric = \"normal_mean_deg\"
value = 1.0
"
exp expect_tol "$base$data$meth[[expect]]
where = { method = \"pf\" }
metric = \"normal_mean_deg\"
value = 1.0
tol = \"rel:abc\"
"
printf 'name = "x"\n# \xff\xfe not utf-8\n' >"$W/non_utf8.toml"
run "dry-run non_utf8" 2 1 "$BIN" run --dry-run "$W/non_utf8.toml"

# Clouds: 1,000 sphere points and 200-point ones scaled to extreme magnitudes.
"$BIN" gen sphere --points 1000 --seed 3 -o "$W/sphere.ply" >/dev/null
"$BIN" gen box --points 2000 --seed 3 -o "$W/box.ply" >/dev/null
"$BIN" convert "$W/sphere.ply" "$W/sphere.xyz" >/dev/null
"$BIN" convert "$W/box.ply" "$W/box.xyz" >/dev/null
scaled() { # scaled SRC.xyz FACTOR OUT.xyz
    awk -v f="$2" '{ printf "%.17g %.17g %.17g\n", $1 * f, $2 * f, $3 * f }' "$1" >"$3"
}
for f in 1e-60 1e80; do
    scaled "$W/sphere.xyz" "$f" "$W/sphere_$f.xyz"
    run "delaunay --validate sphere x $f" 0 60 "$BIN" delaunay --validate "$W/sphere_$f.xyz"
done
# Subnormal: awk cannot print below 1e-308 reliably; python writes them.
python3 - "$W" <<'PY'
import sys
w = sys.argv[1]
pts = [tuple(map(float, l.split()[:3])) for l in open(f"{w}/box.xyz")]
for tag, f in [("subnormal", 1e-310), ("1e-9", 1e-9), ("1e-160", 1e-160)]:
    with open(f"{w}/box_{tag}.xyz", "w") as o:
        for p in pts:
            o.write("%r %r %r\n" % tuple(c * f for c in p))
pts = [tuple(map(float, l.split()[:3])) for l in open(f"{w}/sphere.xyz")]
for tag, f in [("1e200", 1e200), ("1e308", 1.7e308)]:
    with open(f"{w}/sphere_{tag}.xyz", "w") as o:
        for p in pts:
            o.write("%r %r %r\n" % tuple(c * f for c in p))
PY
# eval-features needs a labelled cloud: gt-features on a box sample, as ASCII PLY, scaled.
"$BIN" features --method gt-features "$W/box.ply" -o "$W/lab.ply" >/dev/null
"$BIN" convert "$W/lab.ply" "$W/lab_a.ply" --ply-encoding ascii >/dev/null
python3 - "$W" <<'PY'
import sys
w = sys.argv[1]
lines = open(f"{w}/lab_a.ply").read().split("\n")
end = lines.index("end_header")
for tag, f in [("subnormal", 1e-310), ("1e-9", 1e-9), ("1e-160", 1e-160)]:
    with open(f"{w}/lab_{tag}.ply", "w") as o:
        o.write("\n".join(lines[: end + 1]) + "\n")
        for l in lines[end + 1 :]:
            if not l.strip():
                continue
            v = l.split()
            v[:3] = [repr(float(c) * f) for c in v[:3]]
            o.write(" ".join(v) + "\n")
PY
for t in subnormal 1e-9 1e-160; do
    run "eval-features --reference box (x $t)" "0|2" 60 "$BIN" eval-features --cloud "$W/lab_$t.ply" --reference box
done
for m in ufm ufm-mesh priority-front; do
    for t in 1e200 1e308; do
        kind=reconstruct
        out="$W/o.ply"
        [ "$m" = ufm-mesh ] && kind=normals
        run "$kind $m sphere x $t" "0|2" 60 "$BIN" "$kind" --method "$m" "$W/sphere_$t.xyz" -o "$out"
    done
done
# A PLY whose body is endless zeros (a FIFO fed by /dev/zero: no file size to go by).
for verb in info convert; do
    rm -f "$W/zeros.ply"
    mkfifo "$W/zeros.ply"
    ( { printf 'ply\nformat binary_little_endian 1.0\nelement vertex 4000000000\nproperty float x\nproperty float y\nproperty float z\nend_header\n'; cat /dev/zero; } >"$W/zeros.ply" 2>/dev/null & )
    if [ $verb = info ]; then
        run "info endless-zeros PLY (fifo)" 2 30 "$BIN" info "$W/zeros.ply"
    else
        run "convert endless-zeros PLY (fifo)" 2 30 "$BIN" convert "$W/zeros.ply" "$W/z.obj"
    fi
    # Unblock a writer still waiting on the FIFO.
    timeout 1 cat "$W/zeros.ply" >/dev/null 2>&1
    rm -f "$W/zeros.ply"
done
# 40 million vertices (480 MB, under the 512 MiB stream limit) then more zeros, and an
# ASCII body of endless '0' characters without a line break.
fifo() { # fifo HEADER BODY_CMD
    rm -f "$W/f.ply"
    mkfifo "$W/f.ply"
    ( { printf "$1"; eval "$2"; } >"$W/f.ply" 2>/dev/null & )
}
fifo 'ply\nformat binary_little_endian 1.0\nelement vertex 40000000\nproperty float x\nproperty float y\nproperty float z\nend_header\n' 'cat /dev/zero'
run "info 4e7-vertex PLY + endless zeros (fifo)" 2 30 "$BIN" info "$W/f.ply"
timeout 1 cat "$W/f.ply" >/dev/null 2>&1
zero_chars() { tr '\0' 0 </dev/zero; }
fifo 'ply\nformat ascii 1.0\nelement vertex 10\nproperty float x\nproperty float y\nproperty float z\nend_header\n' zero_chars
run "info ascii PLY, endless '0' line (fifo)" 2 30 "$BIN" info "$W/f.ply"
timeout 1 cat "$W/f.ply" >/dev/null 2>&1
rm -f "$W/f.ply"
# ... and as a 64 MB regular file.
{ printf 'ply\nformat binary_little_endian 1.0\nelement vertex 4000000000\nproperty float x\nproperty float y\nproperty float z\nend_header\n'; head -c 64000000 /dev/zero; } >"$W/zeros_file.ply"
run "info 4e9-vertex PLY, 64 MB zeros" 2 5 "$BIN" info "$W/zeros_file.ply"

# Two concurrent runs into one directory: the second refuses, naming the holder's PID.
cat >"$W/conc.toml" <<T
name = "conc"
seed = 1
seeds = 2
[[datasets]]
name = "s"
shape = "sphere"
points = [1000, 1500]
[[perturbations]]
noise = [0.0, 0.002]
[[methods]]
name = "pf"
[[methods]]
name = "jet"
[report]
plots = false
renders = false
T
mkdir -p "$W/c1" "$W/c2" "$W/c3"
( cd "$W/c1" && "$BIN" run "$W/conc.toml" -j 1 >"$W/c1.out" 2>&1 ) &
first=$!
for _ in $(seq 100); do
    ls "$W"/c1/results/conc/*.lock >/dev/null 2>&1 && break
    sleep 0.05
done
( cd "$W/c1" && run "second concurrent run (same dir)" 2 5 "$BIN" run "$W/conc.toml" )
wait $first
# Shard + merge vs one run: byte-identical rows apart from cost.
"$BIN" run "$W/conc.toml" --shard 0/2 --out "$W/c2/s0" --no-report >/dev/null 2>&1
"$BIN" run "$W/conc.toml" --shard 1/2 --out "$W/c2/s1" --no-report >/dev/null 2>&1
run "merge of 2 shards" 0 60 "$BIN" merge "$W/c2/s0" "$W/c2/s1" --out "$W/c3/merged" --no-report
python3 - "$W/c1/results/conc" "$W/c3/merged" <<'PY' || FAIL=1
import glob, json, sys
def rows(d):
    out = {}
    for f in sorted(glob.glob(d + "/results*.jsonl")):
        for line in open(f):
            r = json.loads(line)
            r.pop("cost", None)
            out[r["key"]] = json.dumps(r, sort_keys=True)
    return out
a, b = rows(sys.argv[1]), rows(sys.argv[2])
same = sum(1 for k in a if b.get(k) == a[k])
print(f"| merge vs one run: rows equal apart from cost | {same}/{len(a)} ({len(b)} merged) | | | |")
sys.exit(0 if a and same == len(a) == len(b) else 1)
PY
echo
[ $FAIL = 0 ] && echo "all cases pass" || echo "SOME CASES FAIL"
exit $FAIL
