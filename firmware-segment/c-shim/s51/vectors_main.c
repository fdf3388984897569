/*
 * vectors_main.c: s51 test harness for segment.c (TEST BUILDS ONLY, never for the LPC938).
 *
 * Runs on the ucsim s51 simulator (plain 8052). It reads a binary vector file through the
 * simulator's I/O port, calls segment.c's functions for each record and prints the results as
 * hex text through the same port. tests/tests/s51_vectors.rs generates the vectors and checks
 * every output line against the Rust crates.
 *
 * The port `sif` at xdata 0xFFFF exists only in the simulator (run with
 * `s51 -t 8052 -q -I if=xram[0xffff],in=vec.bin -G vectors.ihx < /dev/null`): write 'r' then
 * read it to get the next byte of the `in=` file; write 'p' then a byte to print that byte;
 * write 's' to stop the simulation. On a real LPC938, xdata 0xFFxx holds the ADC registers,
 * which is why the port is declared here and nowhere else. s51 quits as soon as its console
 * reads end of input, finished or not: with `< /dev/null` a long run is cut short, so keep
 * stdin open until the end marker has been printed (the Rust test does).
 *
 * Record format (all multi-byte operands big-endian), one output line per record:
 *   0x00 END                                   -> prints the end marker, stops
 *   0x01 PACK angle_hi angle_lo touch          -> word (2 bytes, high first)
 *   0x02 PEC crc byte                          -> seg_pec_update (1 byte)
 *   0x03 OVERSAMPLE 16 x (hi lo)               -> oversample (2 bytes) and adc_fault (1 byte)
 *   0x04 DEBOUNCE_RESET                        -> nothing (empty line)
 *   0x05 DEBOUNCE_STEP raw                     -> debounced bits, touch_stuck (2 bytes)
 *   0x06 DEBOUNCE_RUN raw n_hi n_lo            -> n steps of raw (n >= 1), then as STEP
 *   0x07 TARGET_INIT address address_set       -> nothing (empty line)
 *   0x08 TARGET_PUBLISH word_hi word_lo status -> nothing (empty line)
 *   0x09 TARGET_STEP i2stat rx                 -> tx, flags, then the whole seg_target_t:
 *        address, address_set, pointer, phase, wr_reg, wr_len, wr_payload[0..2], wr_bad,
 *        rd_buf[0..3], rd_len, rd_index, word (high, low), status, counter (21 bytes)
 * Any other opcode prints "?" and stops. Output: the start marker line "<<SEG-BEGIN>>", one
 * line per record (two lowercase hex digits per result byte), then "<<SEG-END>>".
 */
#include <stdint.h>

#include "segment.h"

volatile __xdata __at(0xffff) unsigned char sif;

enum {
    OP_END = 0x00,
    OP_PACK = 0x01,
    OP_PEC = 0x02,
    OP_OVERSAMPLE = 0x03,
    OP_DEBOUNCE_RESET = 0x04,
    OP_DEBOUNCE_STEP = 0x05,
    OP_DEBOUNCE_RUN = 0x06,
    OP_TARGET_INIT = 0x07,
    OP_TARGET_PUBLISH = 0x08,
    OP_TARGET_STEP = 0x09
};

static seg_debounce_t debounce;
static seg_target_t target;
static __xdata uint16_t samples[SEG_OVERSAMPLE_COUNT];

static uint8_t in_byte(void)
{
    sif = 'r';
    return sif;
}

static uint16_t in_word(void)
{
    uint16_t hi = in_byte();
    return (uint16_t)((hi << 8) | in_byte());
}

static void out_char(char c)
{
    sif = 'p';
    sif = (unsigned char)c;
}

static void out_str(const char *s)
{
    while (*s != 0) {
        out_char(*s);
        s++;
    }
}

static void out_hex(uint8_t b)
{
    static const char digits[] = "0123456789abcdef";
    out_char(digits[b >> 4]);
    out_char(digits[b & 0x0Fu]);
}

static void out_debounce(uint8_t stable)
{
    out_hex(stable);
    out_hex(seg_touch_stuck(&debounce));
}

void main(void)
{
    uint8_t op, a, b, i;
    uint16_t w;

    seg_debounce_init(&debounce);
    seg_target_init(&target, SEG_DEFAULT_ADDRESS, 0);
    out_str("\n<<SEG-BEGIN>>\n");
    for (;;) {
        op = in_byte();
        switch (op) {
        case OP_END:
            out_str("<<SEG-END>>\n");
            sif = 's';
            for (;;) {
            }
        case OP_PACK:
            w = in_word();
            a = in_byte();
            w = seg_pack(w, a);
            out_hex((uint8_t)(w >> 8));
            out_hex((uint8_t)w);
            break;
        case OP_PEC:
            a = in_byte();
            b = in_byte();
            out_hex(seg_pec_update(a, b));
            break;
        case OP_OVERSAMPLE:
            for (i = 0; i < SEG_OVERSAMPLE_COUNT; i++) {
                samples[i] = in_word();
            }
            w = seg_oversample(samples);
            out_hex((uint8_t)(w >> 8));
            out_hex((uint8_t)w);
            out_hex(seg_adc_fault(samples));
            break;
        case OP_DEBOUNCE_RESET:
            seg_debounce_init(&debounce);
            break;
        case OP_DEBOUNCE_STEP:
            a = in_byte();
            out_debounce(seg_debounce_step(&debounce, a));
            break;
        case OP_DEBOUNCE_RUN:
            a = in_byte();
            w = in_word();
            b = 0;
            while (w != 0) {
                b = seg_debounce_step(&debounce, a);
                w--;
            }
            out_debounce(b);
            break;
        case OP_TARGET_INIT:
            a = in_byte();
            b = in_byte();
            seg_target_init(&target, a, b);
            break;
        case OP_TARGET_PUBLISH:
            w = in_word();
            a = in_byte();
            seg_target_publish(&target, w, a);
            break;
        case OP_TARGET_STEP:
            a = in_byte();
            b = in_byte();
            a = seg_target_step(&target, a, b, &b);
            out_hex(b);
            out_hex(a);
            out_hex(target.address);
            out_hex(target.address_set);
            out_hex(target.pointer);
            out_hex(target.phase);
            out_hex(target.wr_reg);
            out_hex(target.wr_len);
            out_hex(target.wr_payload[0]);
            out_hex(target.wr_payload[1]);
            out_hex(target.wr_bad);
            out_hex(target.rd_buf[0]);
            out_hex(target.rd_buf[1]);
            out_hex(target.rd_buf[2]);
            out_hex(target.rd_len);
            out_hex(target.rd_index);
            out_hex((uint8_t)(target.word >> 8));
            out_hex((uint8_t)target.word);
            out_hex(target.status);
            out_hex(target.counter);
            break;
        default:
            out_str("?\n");
            sif = 's';
            for (;;) {
            }
        }
        out_char('\n');
    }
}
