#!/bin/bash -eu
# A firmware project's .clusterfuzzlite/build.sh: builds mocosim's firmware_fuzz
# target with the builder's compiler, sanitizers and fuzzing engine, builds the
# firmware with avr-gcc as a release does, and puts the ELF beside the target
# as $OUT/firmware_fuzz.elf, where the target looks for it. The seed corpus is
# recorded host traffic (a session's host bytes: `mocosim decode` shows them).
cd "$SRC/firmware"
make firmware.elf                      # your usual AVR build (avr-gcc, -g for names)
cp firmware.elf "$OUT/firmware_fuzz.elf"

cd "$SRC/mocosim"
CXXFLAGS="${CXXFLAGS//-stdlib=libc++/}"  # the Debian libraries are built against libstdc++
cmake -S . -B "$WORK/mocosim" -G Ninja -DCMAKE_BUILD_TYPE=None \
  -DCMAKE_C_COMPILER="$CC" -DCMAKE_CXX_COMPILER="$CXX" \
  -DCMAKE_C_FLAGS="$CFLAGS" -DCMAKE_CXX_FLAGS="$CXXFLAGS" \
  -DMOCO_FUZZ=ON -DMOCO_LIB_FUZZING_ENGINE="$LIB_FUZZING_ENGINE" \
  -DMOCO_BUILD_TESTS=OFF -DMOCO_BUILD_BENCHMARKS=OFF
cmake --build "$WORK/mocosim" --target firmware_fuzz
cp "$(find "$WORK/mocosim" -type f -name firmware_fuzz -perm -u+x | head -1)" "$OUT/"

# The protocol your firmware speaks (dfmoco when not given) and, when its ELF
# has no .mmcu section, its MCU and clock (atmega328p at 16 MHz when not given).
cat > "$OUT/firmware_fuzz.conf" <<'CONF'
MOCO_FIRMWARE_PROTOCOL=dfmoco
MOCO_FIRMWARE=firmware_fuzz.elf@atmega328p:16000000
CONF
cat > "$OUT/firmware_fuzz.options" <<'OPTIONS'
[libfuzzer]
max_len = 4096
OPTIONS
(cd "$SRC/firmware/fuzz-seeds" && zip -q "$OUT/firmware_fuzz_seed_corpus.zip" ./*)
