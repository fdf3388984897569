/*
 * segment.h: the antenna segment's logic in portable C (C99/C11, SDCC-compatible), bit-exact
 * with the Rust crates `antenna-protocol` and `firmware-segment`. The behaviour is specified in
 * firmware-segment/README.md. No dynamic memory, no floating point, no library calls.
 */
#ifndef ANTENNA_SEGMENT_H
#define ANTENNA_SEGMENT_H

#include <stdint.h>

#define SEG_FW_MAJOR 1u
#define SEG_FW_MINOR 0u
#define SEG_DEFAULT_ADDRESS 0x77u
#define SEG_MIN_ADDRESS 0x08u
#define SEG_MAX_ADDRESS 0x77u
#define SEG_OVERSAMPLE_COUNT 16u
#define SEG_TOUCH_STUCK_SAMPLES 60000u

#define SEG_REG_WORD 0x00u
#define SEG_REG_VERSION 0x01u
#define SEG_REG_STATUS 0x02u
#define SEG_REG_COUNTER 0x03u
#define SEG_REG_ASSIGN 0x10u

#define SEG_STATUS_ADC_FAULT 0x01u
#define SEG_STATUS_TOUCH_STUCK 0x02u
#define SEG_STATUS_ADDRESS_NOT_SET 0x04u

/* Flags returned by seg_target_step. */
#define SEG_STEP_ACK_NEXT 0x01u
#define SEG_STEP_ADDRESS_CHANGED 0x02u

/* (angle12 << 4) | touch, with angle masked to 12 bits and touch to 4. */
uint16_t seg_pack(uint16_t angle12, uint8_t touch);

/* SMBus PEC: fold one byte into a CRC-8 (polynomial 0x07, MSB first). */
uint8_t seg_pec_update(uint8_t crc, uint8_t byte);

/* (sum of the 16 conversions, each masked to 10 bits) >> 2. */
uint16_t seg_oversample(const uint16_t *samples16);

/* 1 when any of the 16 conversions (masked to 10 bits) is 0 or 1023, else 0. */
uint8_t seg_adc_fault(const uint16_t *samples16);

typedef struct {
    uint8_t h1;        /* previous raw read */
    uint8_t h2;        /* the one before */
    uint8_t stable;    /* debounced touch bits */
    uint16_t held[4];  /* consecutive samples each debounced bit has read 1, saturating */
} seg_debounce_t;

void seg_debounce_init(seg_debounce_t *d);
/* Feeds one raw 4-bit read (higher bits ignored); returns the debounced bits. */
uint8_t seg_debounce_step(seg_debounce_t *d, uint8_t raw);
/* 1 when any bit has been held for SEG_TOUCH_STUCK_SAMPLES or more. */
uint8_t seg_touch_stuck(const seg_debounce_t *d);

typedef struct {
    uint8_t address;      /* 7-bit address the segment answers at */
    uint8_t address_set;  /* 0 while still at the default address */
    uint8_t pointer;      /* register for the next read */
    uint8_t phase;        /* 0 idle, 1 writing, 2 reading */
    uint8_t wr_reg;
    uint8_t wr_len;       /* bytes received in this write, register number included */
    uint8_t wr_payload[2];
    uint8_t wr_bad;
    uint8_t rd_buf[3];    /* latched data bytes and their PEC */
    uint8_t rd_len;
    uint8_t rd_index;
    uint16_t word;        /* last published sample word */
    uint8_t status;       /* last published status flags; a read of register 0x02 returns
                             them with bit 2 taken from !address_set at that moment */
    uint8_t counter;      /* sample counter, wraps */
} seg_target_t;

void seg_target_init(seg_target_t *t, uint8_t address, uint8_t address_set);
/* A new sample: stores word and status, counter += 1 (wrapping). */
void seg_target_publish(seg_target_t *t, uint16_t word, uint8_t status);
/* One bus event. Writes the byte to transmit to *tx (0xFF when there is none) and returns
 * SEG_STEP_* flags. */
uint8_t seg_target_step(seg_target_t *t, uint8_t i2stat, uint8_t rx, uint8_t *tx);

#endif
