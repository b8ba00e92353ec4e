// Board file: any other board on the host core: the Arduino API and the
// generic timer (TimerOne.h), nothing of a vendor's own.
#define MOCO_BOARD_GENERIC 1
#ifndef F_CPU
#define F_CPU 16000000L
#endif
