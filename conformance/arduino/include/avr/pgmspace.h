// PROGMEM on the host core: flash is ordinary memory, so the _P functions and
// pgm_read_*() read it directly.
#ifndef MOCO_CONFORMANCE_ARDUINO_INCLUDE_AVR_PGMSPACE_H_
#define MOCO_CONFORMANCE_ARDUINO_INCLUDE_AVR_PGMSPACE_H_

#include <stdint.h>
#include <string.h>

#define PROGMEM
#define PGM_P const char*
#define PSTR(s) (s)
#define pgm_read_byte(addr) (*(const uint8_t*)(addr))
#define pgm_read_word(addr) (*(const uint16_t*)(addr))
#define pgm_read_dword(addr) (*(const uint32_t*)(addr))
#define pgm_read_float(addr) (*(const float*)(addr))
#define pgm_read_ptr(addr) (*(void* const*)(addr))
#define pgm_read_byte_near(addr) pgm_read_byte(addr)
#define pgm_read_word_near(addr) pgm_read_word(addr)
#define strcpy_P strcpy
#define strncpy_P strncpy
#define strcmp_P strcmp
#define strncmp_P strncmp
#define strlen_P strlen
#define memcpy_P memcpy
#define strcat_P strcat
#define sprintf_P sprintf
#define snprintf_P snprintf

#endif  // MOCO_CONFORMANCE_ARDUINO_INCLUDE_AVR_PGMSPACE_H_
