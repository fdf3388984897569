/*
 * segment.c: the antenna segment's logic in portable C99 (SDCC-compatible), bit-exact with the
 * Rust crate `firmware-segment` (see firmware-segment/README.md for the behaviour and
 * segment.h for the API). No tables, no library calls: it fits the P89LPC938.
 */
#include "segment.h"

#define SEG_ANGLE_MASK 0x0FFFu
#define SEG_TOUCH_MASK 0x0Fu
#define SEG_ADC_MASK 0x03FFu
#define SEG_IDLE_BYTE 0xFFu

#define SEG_PHASE_IDLE 0u
#define SEG_PHASE_WRITING 1u
#define SEG_PHASE_READING 2u

uint16_t seg_pack(uint16_t angle12, uint8_t touch)
{
    return (uint16_t)(((uint16_t)(angle12 & SEG_ANGLE_MASK) << 4) | (uint16_t)(touch & SEG_TOUCH_MASK));
}

uint8_t seg_pec_update(uint8_t crc, uint8_t byte)
{
    uint8_t bit;
    crc ^= byte;
    for (bit = 0; bit < 8u; bit++) {
        if (crc & 0x80u) {
            crc = (uint8_t)((uint8_t)(crc << 1) ^ 0x07u);
        } else {
            crc = (uint8_t)(crc << 1);
        }
    }
    return crc;
}

uint16_t seg_oversample(const uint16_t *samples16)
{
    uint16_t sum = 0;
    uint8_t i;
    for (i = 0; i < SEG_OVERSAMPLE_COUNT; i++) {
        sum = (uint16_t)(sum + (samples16[i] & SEG_ADC_MASK));
    }
    return (uint16_t)(sum >> 2);
}

uint8_t seg_adc_fault(const uint16_t *samples16)
{
    uint8_t i;
    for (i = 0; i < SEG_OVERSAMPLE_COUNT; i++) {
        uint16_t s = (uint16_t)(samples16[i] & SEG_ADC_MASK);
        if (s == 0u || s == SEG_ADC_MASK) {
            return 1u;
        }
    }
    return 0u;
}

void seg_debounce_init(seg_debounce_t *d)
{
    uint8_t i;
    d->h1 = 0;
    d->h2 = 0;
    d->stable = 0;
    for (i = 0; i < 4u; i++) {
        d->held[i] = 0;
    }
}

uint8_t seg_debounce_step(seg_debounce_t *d, uint8_t raw)
{
    uint8_t agree;
    uint8_t i;
    raw &= SEG_TOUCH_MASK;
    agree = (uint8_t)(~((raw ^ d->h1) | (raw ^ d->h2)) & SEG_TOUCH_MASK);
    d->stable = (uint8_t)((d->stable & (uint8_t)~agree) | (raw & agree));
    d->h2 = d->h1;
    d->h1 = raw;
    for (i = 0; i < 4u; i++) {
        if (d->stable & (uint8_t)(1u << i)) {
            if (d->held[i] != 0xFFFFu) {
                d->held[i]++;
            }
        } else {
            d->held[i] = 0;
        }
    }
    return d->stable;
}

uint8_t seg_touch_stuck(const seg_debounce_t *d)
{
    uint8_t i;
    for (i = 0; i < 4u; i++) {
        if (d->held[i] >= SEG_TOUCH_STUCK_SAMPLES) {
            return 1u;
        }
    }
    return 0u;
}

void seg_target_init(seg_target_t *t, uint8_t address, uint8_t address_set)
{
    uint8_t *p = (uint8_t *)t;
    uint8_t i;
    for (i = 0; i < (uint8_t)sizeof(seg_target_t); i++) {
        p[i] = 0;
    }
    t->address = address;
    t->address_set = address_set ? 1u : 0u;
    t->pointer = SEG_REG_WORD;
    t->phase = SEG_PHASE_IDLE;
}

void seg_target_publish(seg_target_t *t, uint16_t word, uint8_t status)
{
    t->word = word;
    t->status = status;
    t->counter++;
}

/* Drops the transfer in progress: every write and read field back to zero. */
static void seg_clear_transfer(seg_target_t *t)
{
    t->wr_reg = 0;
    t->wr_len = 0;
    t->wr_payload[0] = 0;
    t->wr_payload[1] = 0;
    t->wr_bad = 0;
    t->rd_buf[0] = 0;
    t->rd_buf[1] = 0;
    t->rd_buf[2] = 0;
    t->rd_len = 0;
    t->rd_index = 0;
}

static uint8_t seg_known_register(uint8_t reg)
{
    return (uint8_t)(reg <= SEG_REG_COUNTER || reg == SEG_REG_ASSIGN);
}

/* Latches the pointer register's bytes and their PEC (over the read address byte and the
 * data bytes) into rd_buf. */
static void seg_latch(seg_target_t *t)
{
    uint8_t len;
    uint8_t crc;
    uint8_t i;
    switch (t->pointer) {
    case SEG_REG_VERSION:
        t->rd_buf[0] = (uint8_t)SEG_FW_MAJOR;
        t->rd_buf[1] = (uint8_t)SEG_FW_MINOR;
        len = 2;
        break;
    case SEG_REG_STATUS:
        t->rd_buf[0] = (uint8_t)(t->address_set ? (t->status & (uint8_t)~SEG_STATUS_ADDRESS_NOT_SET)
                                                : (t->status | SEG_STATUS_ADDRESS_NOT_SET));
        len = 1;
        break;
    case SEG_REG_COUNTER:
        t->rd_buf[0] = t->counter;
        len = 1;
        break;
    default: /* SEG_REG_WORD: the pointer never holds anything else */
        t->rd_buf[0] = (uint8_t)(t->word >> 8);
        t->rd_buf[1] = (uint8_t)(t->word & 0xFFu);
        len = 2;
        break;
    }
    crc = seg_pec_update(0, (uint8_t)((uint8_t)(t->address << 1) | 1u));
    for (i = 0; i < len; i++) {
        crc = seg_pec_update(crc, t->rd_buf[i]);
    }
    t->rd_buf[len] = crc;
    t->rd_len = (uint8_t)(len + 1u);
}

/* STOP after a good write: a lone readable register sets the pointer; a complete assignment
 * with the right complement and an assignable address moves the segment. Returns 1 when the
 * address changed. */
static uint8_t seg_commit_write(seg_target_t *t)
{
    if (t->wr_reg == SEG_REG_ASSIGN) {
        uint8_t a = t->wr_payload[0];
        uint8_t complement = (uint8_t)~a;
        if (t->wr_len == 3u && t->wr_payload[1] == complement && a >= SEG_MIN_ADDRESS &&
            a <= SEG_MAX_ADDRESS) {
            t->address = a;
            t->address_set = 1;
            return 1u;
        }
    } else if (t->wr_len == 1u && t->wr_reg <= SEG_REG_COUNTER) {
        t->pointer = t->wr_reg;
    }
    return 0u;
}

uint8_t seg_target_step(seg_target_t *t, uint8_t i2stat, uint8_t rx, uint8_t *tx)
{
    uint8_t flags = SEG_STEP_ACK_NEXT;
    *tx = SEG_IDLE_BYTE;
    switch (i2stat) {
    case 0x60: case 0x68: case 0x70: case 0x78: /* addressed for write */
        seg_clear_transfer(t);
        t->phase = SEG_PHASE_WRITING;
        break;
    case 0x80: case 0x90: /* data received, ACK returned */
        if (t->phase != SEG_PHASE_WRITING) {
            break;
        }
        if (t->wr_len == 0u) {
            t->wr_reg = rx;
            if (!seg_known_register(rx)) {
                t->wr_bad = 1;
            }
        } else if (t->wr_reg == SEG_REG_ASSIGN && t->wr_len <= 2u) {
            t->wr_payload[t->wr_len - 1u] = rx;
        } else {
            t->wr_bad = 1; /* over-long write */
        }
        if (t->wr_len != 0xFFu) {
            t->wr_len++;
        }
        if (t->wr_bad || t->wr_reg != SEG_REG_ASSIGN || t->wr_len >= 3u) {
            flags = 0;
        }
        break;
    case 0x88: case 0x98: /* data received, NACK returned */
        if (t->phase != SEG_PHASE_WRITING) {
            break;
        }
        t->wr_bad = 1;
        if (t->wr_len != 0xFFu) {
            t->wr_len++;
        }
        flags = 0;
        break;
    case 0xA0: /* STOP or repeated START */
        if (t->phase == SEG_PHASE_WRITING && !t->wr_bad) {
            if (seg_commit_write(t)) {
                flags |= SEG_STEP_ADDRESS_CHANGED;
            }
        } else if (t->phase == SEG_PHASE_READING) {
            t->pointer = SEG_REG_WORD;
        }
        seg_clear_transfer(t);
        t->phase = SEG_PHASE_IDLE;
        break;
    case 0xA8: case 0xB0: /* addressed for read: load the first byte */
        seg_clear_transfer(t);
        seg_latch(t);
        t->phase = SEG_PHASE_READING;
        t->rd_index = 1;
        *tx = t->rd_buf[0];
        break;
    case 0xB8: /* byte sent and ACKed: load the next */
        if (t->phase == SEG_PHASE_READING && t->rd_index < t->rd_len) {
            *tx = t->rd_buf[t->rd_index];
            t->rd_index++;
        }
        break;
    case 0xC0: case 0xC8: /* controller finished reading */
        t->pointer = SEG_REG_WORD;
        seg_clear_transfer(t);
        t->phase = SEG_PHASE_IDLE;
        break;
    case 0x00: /* bus error: the transfer is dropped */
        seg_clear_transfer(t);
        t->phase = SEG_PHASE_IDLE;
        break;
    default: /* controller-mode codes, 0xF8: nothing */
        break;
    }
    return flags;
}
