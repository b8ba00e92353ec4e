#!/bin/bash -eu
# Builds every libFuzzer target of the project (the codecs: dmc_fuzz,
# dfmoco_fuzz, stackshot_fuzz; the sessions against in-process devices:
# dmc_session_fuzz, dfmoco_session_fuzz, stackshot_session_fuzz; where simavr
# and avr-gcc are installed, firmware_fuzz with our DFMoco firmware) into $OUT,
# each with its seed corpus from fixtures/fuzz-seeds/<target without _fuzz>
# as $OUT/<target>_seed_corpus.zip.
#
# In ClusterFuzzLite / OSS-Fuzz (.clusterfuzzlite/Dockerfile) the builder
# sets CC, CXX, CFLAGS, CXXFLAGS (sanitizers included), LIB_FUZZING_ENGINE,
# OUT and WORK. It also runs here, outside Docker, with clang:
#   OUT=/tmp/fuzz-out .clusterfuzzlite/build.sh
# (defaults: CC=clang, CXX=clang++, LIB_FUZZING_ENGINE=-fsanitize=fuzzer,
# ASan+UBSan flags, WORK=build/clusterfuzzlite); ci/clusterfuzzlite-build
# does this in CI. MOCO_JOBS bounds the build's parallel jobs; MOCO_WERROR=ON
# makes warnings errors (CI). MOCO_FUZZ_SKIP (a bash regex) leaves out the
# targets it matches (CI builds the codec targets here and links the others
# in its asan build, see ci/test).
cd "$(dirname "$0")/.."

: "${OUT:?set OUT to the folder that receives the fuzz targets}"
: "${CC:=clang}"
: "${CXX:=clang++}"
: "${LIB_FUZZING_ENGINE:=-fsanitize=fuzzer}"
# Outside the builder the flags follow OSS-Fuzz's own defaults: -O1 and line
# tables only (-gline-tables-only: a crash's stack still names file:line; the
# full debug information of -g costs compile time and nothing a report shows).
sanitize="-fsanitize=address,undefined -fno-sanitize-recover=undefined -fsanitize=fuzzer-no-link"
: "${CFLAGS:=-O1 -gline-tables-only -fno-omit-frame-pointer $sanitize}"
: "${CXXFLAGS:=-O1 -gline-tables-only -fno-omit-frame-pointer $sanitize}"
work="${WORK:-$PWD/build}/clusterfuzzlite"
# The Debian/Ubuntu libraries the targets link (Bullet) are built against
# libstdc++; the builder's -stdlib=libc++ (needed only for MemorySanitizer,
# which project.yaml does not ask for) would not link with them.
CXXFLAGS="${CXXFLAGS//-stdlib=libc++/}"

mkdir -p "$OUT" "$work"
cmake -S . -B "$work" -G Ninja \
  -DCMAKE_BUILD_TYPE=None \
  -DCMAKE_C_COMPILER="$CC" -DCMAKE_CXX_COMPILER="$CXX" \
  -DCMAKE_C_FLAGS="$CFLAGS" -DCMAKE_CXX_FLAGS="$CXXFLAGS" \
  -DMOCO_FUZZ=ON -DMOCO_LIB_FUZZING_ENGINE="$LIB_FUZZING_ENGINE" \
  -DMOCO_WERROR="${MOCO_WERROR:-OFF}" \
  -DMOCO_BUILD_TESTS=OFF -DMOCO_BUILD_BENCHMARKS=OFF >"$work/configure.log" ||
  { cat "$work/configure.log"; exit 1; }

mapfile -t defined < <(cmake --build "$work" --target help |
  sed -n -e 's/^\([a-z_0-9]*_fuzz\): .*/\1/p' -e 's/^\.\.\. \([a-z_0-9]*_fuzz\)$/\1/p' | sort -u)
targets=()
for t in "${defined[@]}"; do
  if [ -z "${MOCO_FUZZ_SKIP:-}" ] || ! [[ "$t" =~ $MOCO_FUZZ_SKIP ]]; then targets+=("$t"); fi
done
if [ ${#targets[@]} -eq 0 ]; then
  echo "build.sh: the build defines no *_fuzz target" >&2
  exit 1
fi
cmake --build "$work" -j "${MOCO_JOBS:-$(nproc)}" --target "${targets[@]}"

for t in "${targets[@]}"; do
  binary=$(find "$work" -type f -name "$t" -perm -u+x | head -1)
  [ -n "$binary" ] || { echo "build.sh: $t was not built" >&2; exit 1; }
  cp "$binary" "$OUT/$t"
  seeds="fixtures/fuzz-seeds/${t%_fuzz}"
  if [ -d "$seeds" ]; then
    rm -f "$OUT/${t}_seed_corpus.zip"
    (cd "$seeds" && find . -type f -print0 | sort -z | xargs -0 python3 -m zipfile -c \
      "$OUT/${t}_seed_corpus.zip")
  fi
  echo "build.sh: $OUT/$t"
done

# The firmware target fuzzes the AVR image beside it ($OUT/firmware_fuzz.elf):
# here our own DFMoco test firmware. A firmware project copies its own ELF
# there (docs/firmware-ci.md "ClusterFuzzLite").
if [ -x "$OUT/firmware_fuzz" ]; then
  elf=$(find "$work" -type f -name dfmoco.elf -path '*dfmoco_avr*' | head -1)
  [ -n "$elf" ] || { echo "build.sh: the DFMoco test firmware was not built" >&2; exit 1; }
  cp "$elf" "$OUT/firmware_fuzz.elf"
  echo "build.sh: $OUT/firmware_fuzz.elf (from $elf)"
fi
