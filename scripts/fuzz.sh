#!/usr/bin/env bash
# Runs every parser's fuzz target (fuzz/fuzz_targets) for RUNS executions each (default 10^6)
# with libFuzzer through cargo-fuzz on the nightly toolchain, seeded from the repository's
# own files, and prints one line per target: executions, seconds, crashes. Not part of CI.
#   scripts/fuzz.sh            all targets, 10^6 runs each
#   RUNS=100000 scripts/fuzz.sh csv_rows tum_parse
# A crash leaves its input in fuzz/artifacts/TARGET/ and makes the script exit non-zero.
set -uo pipefail
cd "$(dirname "$0")/.."
RUNS=${RUNS:-1000000}
command -v cargo-fuzz >/dev/null 2>&1 || cargo install cargo-fuzz
rustup toolchain list | grep -q nightly || { echo "fuzz: needs the nightly toolchain (rustup toolchain install nightly)" >&2; exit 1; }
targets=("$@")
if [ ${#targets[@]} -eq 0 ]; then
  mapfile -t targets < <(sed -n 's/^name = "\(.*\)"/\1/p' fuzz/Cargo.toml | grep -v '^ocellus-fuzz$')
fi

# Seed corpora: real files of each format, so that the fuzzer starts inside the format.
seed() {
  local t=$1 dir=fuzz/corpus/$1
  mkdir -p "$dir"
  case $t in
    decode_image) cp testdata/reference/*.png testdata/rocket.jpg "$dir"/ 2>/dev/null
                  printf 'P5\n4 2\n255\n\0\1\2\3\4\5\6\7' > "$dir/small.pgm" ;;
    npy_parse) cp testdata/reference/*.npy "$dir"/ ;;
    pfm_parse) head -c 4096 testdata/motorcycle_disp.pfm > "$dir/head.pfm"
               printf 'Pf\n2 2\n-1.0\n' > "$dir/tiny.pfm"; head -c 16 /dev/zero >> "$dir/tiny.pfm" ;;
    points_parse|csv_rows) printf 'x,y\n1,2\n3.5;4\n' > "$dir/points.csv"; printf '\x04view,X,Y,u,v\n0,1,2,3,4\n' > "$dir/rows.csv" ;;
    tum_parse) printf '0 0 0 0 0 0 0 1\n0.005 0.01 0 0 0 0 0.1 0.995\n' > "$dir/t.tum" ;;
    y4m_parse) printf 'YUV4MPEG2 W4 H2 F30:1 C444\nFRAME\n' > "$dir/a.y4m"; head -c 24 /dev/zero >> "$dir/a.y4m" ;;
    saliency_config) printf 'map_level = 3\n[gabor]\nsize = 15\n' > "$dir/c.toml"
                     for b in target/release/ocellus target/debug/ocellus; do [ -x $b ] && $b saliency --print-config > "$dir/full.toml" && break; done ;;
    camera_file) printf 'image_size = [640, 480]\n[intrinsics]\nfx = 600.0\nfy = 600.0\ncx = 319.5\ncy = 239.5\nskew = 0.0\n[distortion]\nk1 = -0.2\n' > "$dir/c.toml"
                 printf '{"intrinsics": {"fx": 600, "fy": 600, "cx": 320, "cy": 240, "skew": 0}}' > "$dir/c.json" ;;
  esac
}

status=0
printf '%-16s %12s %8s %8s\n' target executions seconds crashes
for t in "${targets[@]}"; do
  seed "$t"
  log=$(mktemp)
  start=$(date +%s)
  (cd fuzz && cargo +nightly fuzz run "$t" "corpus/$t" -- -runs="$RUNS" -rss_limit_mb=4096 -max_len=65536) >"$log" 2>&1
  rc=$?
  secs=$(( $(date +%s) - start ))
  execs=$(grep -o 'Done [0-9]* runs' "$log" | grep -o '[0-9]*' | tail -1)
  crashes=$(ls "fuzz/artifacts/$t" 2>/dev/null | wc -l)
  printf '%-16s %12s %8s %8s\n' "$t" "${execs:-?}" "$secs" "$crashes"
  if [ $rc -ne 0 ] || [ "$crashes" -gt 0 ]; then
    status=1
    grep -E 'panicked|ERROR|SUMMARY' "$log" | head -5
  fi
  rm -f "$log"
done
exit $status
