#!/usr/bin/env bash
# Browser tests of the web viewer (called by .ci/run): Debian's Chromium,
# headless, driven by playwright-core, against
#   1. a small Node static server (web/tests/lib.mjs),
#   2. nginx (Debian package) on a loopback port, config in a temp folder,
#   3. `lodkit serve`, when the binary has that command.
# Installs what is missing (chromium, nginx-light, npm) with apt-get.
# Output (screenshots, results.json per server): target/web-test/.
# LODKIT_WEB_BENCH=1 also runs the wasm-vs-native timings (web/tests/bench.mjs)
# and the load test of `lodkit serve` (web/tests/serve-load.mjs).
set -euo pipefail
cd "$(dirname "$0")/.."
root=$PWD
work=$root/target/web-test
mkdir -p "$work"
start=$(date +%s)

missing=()
[ -x /usr/bin/chromium ] || missing+=(chromium)
command -v nginx >/dev/null 2>&1 || [ -x /usr/sbin/nginx ] || missing+=(nginx-light)
command -v npm >/dev/null 2>&1 || missing+=(npm)
if [ ${#missing[@]} -gt 0 ]; then
  echo "== apt-get install ${missing[*]}"
  sudo=""
  [ "$(id -u)" = 0 ] || sudo=sudo
  $sudo apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $sudo apt-get install -y -qq "${missing[@]}" >/dev/null
fi
nginx_bin=$(command -v nginx || echo /usr/sbin/nginx)

echo "== release binary and the viewer"
cargo build --release --quiet -p lodkit-cli
cargo build --release --quiet -p lodkit-wasm --example native
lodkit=$root/target/release/lodkit
native=$root/target/release/examples/native
scripts/build-web.sh "$work/site"
(cd web && { [ -d node_modules/playwright-core ] || npm ci --no-audit --no-fund --ignore-scripts --loglevel=error; })

echo "== models (lodkit build of the shipped bunny)"
models=$work/models
if [ ! -f "$models/report.md" ] || [ "$lodkit" -nt "$models/report.md" ]; then
  rm -rf "$models"
  "$lodkit" --quiet build data/models/stanford_bunny.ply --out "$models" >/dev/null
fi
stem=stanford_bunny
# A larger stream (a 1M-triangle blob, ~450 KB): at 1 Mbit/s its first
# level must show before a tenth of it is in, a margin of a third of a
# second that the bunny's 35 KB stream (3.5 KB, a few packets) cannot give.
if [ ! -f "$models/blob_1m.pop" ]; then
  "$native" blob 1000000 "$work/blob_1m.ply"
  "$lodkit" --quiet pop encode "$work/blob_1m.ply" -o "$models/blob_1m.pop"
  rm -f "$work/blob_1m.ply"
fi
# A coloured point cloud (a bumpy sphere, 40,000 points, colours by
# position): its `.mco` and its `.pop`, for the checks of other input kinds.
if [ ! -f "$models/cloud.mco" ] || [ "$lodkit" -nt "$models/cloud.mco" ]; then
  node -e '
const n = 40000, lines = [];
for (let i = 0; i < n; i++) {
  const z = 1 - (2 * (i + 0.5)) / n, r = Math.sqrt(1 - z * z), a = i * 2.399963229728653;
  const x = r * Math.cos(a), y = r * Math.sin(a);
  const s = 1 + 0.08 * Math.sin(5 * x) * Math.sin(4 * y) * Math.sin(3 * z);
  const c = [x, y, z].map((v) => Math.round(40 + 200 * (v + 1) / 2));
  lines.push(`${(x * s).toFixed(6)} ${(y * s).toFixed(6)} ${(z * s).toFixed(6)} ${c.join(" ")}`);
}
process.stdout.write(`ply\nformat ascii 1.0\nelement vertex ${n}\nproperty float x\nproperty float y\nproperty float z\nproperty uchar red\nproperty uchar green\nproperty uchar blue\nend_header\n${lines.join("\n")}\n`);
' > "$work/cloud.ply"
  "$lodkit" --quiet mco build "$work/cloud.ply" -o "$models/cloud.mco"
  "$lodkit" --quiet pop encode "$work/cloud.ply" -o "$models/cloud.pop"
fi
# The .mco decoder of the browser under Node: the bunny's model and a
# coloured point cloud's (an open surface, its root cube holds triangles).
node web/tests/mco-decode.mjs --write-sheet "$work/sheet.ply"
"$lodkit" --quiet mco build "$work/sheet.ply" -o "$work/sheet.mco"
LODKIT_WASM=$work/site/lodkit/lodkit.wasm node web/tests/mco-decode.mjs "$models/$stem.mco" "$work/sheet.mco:colors"
# The finest level, as the CLI reports it.
level=$("$lodkit" pop stats "$models/$stem.pop" --json | node -e 'let s="";process.stdin.on("data",d=>s+=d).on("end",()=>{const j=JSON.parse(s);console.log(j.depth)})')
"$native" digest "$models/$stem.pop" "$level" "$models/$stem.mco" 20000 > "$work/native.json"
"$lodkit" pop decode "$models/$stem.pop" --level "$level" -o "$work/pop_level.ply" 2> "$work/pop_decode.txt" || true
"$lodkit" mco extract "$models/$stem.mco" --triangles 20000 -o "$work/mco_cut.ply" 2> "$work/mco_extract.txt" || true
"$lodkit" info "$models/$stem.ply" --json > "$work/ply_info.json"
node -e '
const fs = require("fs");
const [native, info, lods, popTxt, mcoTxt, out] = process.argv.slice(1);
const ref = JSON.parse(fs.readFileSync(native, "utf8"));
// The CLI prints its own counts: they must agree with the library calls.
const popCli = /(\d+) triangles/.exec(fs.readFileSync(popTxt, "utf8"));
const mcoCli = /: (\d+) triangles/.exec(fs.readFileSync(mcoTxt, "utf8"));
if (popCli && +popCli[1] !== ref.pop.triangles) throw new Error(`pop decode says ${popCli[1]} triangles, native ${ref.pop.triangles}`);
if (mcoCli && +mcoCli[1] !== ref.mco.triangles) throw new Error(`mco extract says ${mcoCli[1]} triangles, native ${ref.mco.triangles}`);
ref.ply_faces = JSON.parse(fs.readFileSync(info, "utf8")).faces;
const l = JSON.parse(fs.readFileSync(lods, "utf8"));
// Level 0 of the chain GLB is the input itself (the MSFT_lod base node).
ref.chain = [{ level: 0, triangles: ref.ply_faces }].concat(l.levels.map((v, i) => ({ level: i + 1, triangles: v.triangles })));
ref.files = { pop: "stanford_bunny.pop", mco: "stanford_bunny.mco", chain: "lods/" + l.glb, ply: "stanford_bunny.ply", bigPop: "blob_1m.pop", colouredMco: "cloud.mco", cloudPop: "cloud.pop" };
fs.writeFileSync(out, JSON.stringify(ref, null, 1));
' "$work/native.json" "$work/ply_info.json" "$models/lods/lods.json" "$work/pop_decode.txt" "$work/mco_extract.txt" "$work/ref.json"

export LODKIT_WEB_SITE=$work/site LODKIT_WEB_MODELS=$models LODKIT_WEB_REF=$work/ref.json
status=0

free_port() { node -e 'const s=require("net").createServer().listen(0,"127.0.0.1",()=>{console.log(s.address().port);s.close()})'; }

echo "== browser tests: Node static server"
LODKIT_WEB_OUT=$work/static node web/tests/viewer.test.mjs || status=1

echo "== browser tests: nginx"
ngx=$(mktemp -d)
port=$(free_port)
cat > "$ngx/nginx.conf" <<CONF
worker_processes 1;
daemon off;
pid $ngx/nginx.pid;
error_log $ngx/error.log warn;
events { worker_connections 128; }
http {
  include /etc/nginx/mime.types;
  access_log off;
  client_body_temp_path $ngx/body;
  proxy_temp_path $ngx/proxy;
  fastcgi_temp_path $ngx/fastcgi;
  uwsgi_temp_path $ngx/uwsgi;
  scgi_temp_path $ngx/scgi;
  server {
    listen 127.0.0.1:$port;
    root $work/site;
    location /models/ { alias $models/; }
  }
}
CONF
"$nginx_bin" -p "$ngx" -c "$ngx/nginx.conf" &
ngx_pid=$!
trap 'kill $ngx_pid 2>/dev/null || true; rm -rf "$ngx"' EXIT
for _ in $(seq 50); do node -e 'require("http").get(process.argv[1],r=>process.exit(0)).on("error",()=>process.exit(1))' "http://127.0.0.1:$port/" && break; sleep 0.1; done
LODKIT_WEB_BASE=http://127.0.0.1:$port LODKIT_WEB_OUT=$work/nginx node web/tests/viewer.test.mjs || status=1
kill $ngx_pid 2>/dev/null || true
wait $ngx_pid 2>/dev/null || true

if "$lodkit" serve --help >/dev/null 2>&1; then
  echo "== browser tests: lodkit serve"
  port=$(free_port)
  "$lodkit" serve "$models" --port "$port" > "$work/serve.log" 2>&1 &
  serve_pid=$!
  trap 'kill $serve_pid 2>/dev/null || true' EXIT
  for _ in $(seq 100); do node -e 'require("http").get(process.argv[1],r=>process.exit(0)).on("error",()=>process.exit(1))' "http://127.0.0.1:$port/" && break; sleep 0.1; done
  LODKIT_WEB_BASE=http://127.0.0.1:$port LODKIT_WEB_OUT=$work/serve node web/tests/viewer.test.mjs || status=1
  kill $serve_pid 2>/dev/null || true
fi

if [ "${LODKIT_WEB_BENCH:-0}" = 1 ]; then
  echo "== wasm vs native timings"
  LODKIT_WEB_NATIVE=$native LODKIT_WEB_BENCH_POP=${LODKIT_WEB_BENCH_POP:-$stem.pop,blob_1m.pop} \
    LODKIT_WEB_BENCH_BUDGET=${LODKIT_WEB_BENCH_BUDGET:-20000} node web/tests/bench.mjs || status=1
  node web/tests/serve-load.mjs "$lodkit" "$models" "$stem.mco" 64 200 || status=1
fi
echo "== web step: $(( $(date +%s) - start )) s"
exit $status
