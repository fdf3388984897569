/*
 * main.c: the P89LPC938 binding of the antenna segment firmware (SDCC, mcs51 small model).
 *
 * Thin: register setup, the I2C (SI) and keypad (KBI) interrupt routines, the sampling main
 * loop and the data-EEPROM store of the assigned address. All the logic (oversampling, ADC
 * fault, debouncing, touch stuck, the I2C target state machine, the word) is segment.c, which
 * is tested bit-exact against the Rust crates on the s51 simulator; nothing here decides
 * anything the contract (firmware-segment/README.md) specifies.
 *
 * Build: firmware-segment/c-shim/build-sdcc.sh (compiles everything with --nooverlay: the SI
 * routine calls segment.c functions, and SDCC would otherwise overlay the locals of leaf
 * functions called from the interrupt with those called from the main loop).
 *
 * Clock: the internal RC oscillator, CCLK = 7.373 MHz; timers count PCLK = CCLK / 2.
 *
 * Board assumptions (one place to change them, check against the segment's schematic and the
 * LPC938 pinout): the four touch switches pull KB0..KB3 (P0.0..P0.3) low on contact (bit 0 the
 * most proximal); the Hall sensor's analog output is on ADC0 input SEG_HALL_CHANNEL; I2C on
 * P1.2 (SCL) and P1.3 (SDA).
 */
#include <stdint.h>

#include <p89lpc938.h>

#include "segment.h"

/* ---- board configuration --------------------------------------------------------------- */

#define SEG_HALL_CHANNEL 7u   /* ADC0 input the Hall sensor drives (AD07) */
#define TOUCH_PINS_MASK 0x0Fu /* KB0..KB3 = P0.0..P0.3, bit 0 the most proximal switch */

/* Timer 0, mode 1 (16 bit), reloaded in its interrupt: 1 ms at PCLK = 7.3728 MHz / 2
 * = 3686.4 kHz is 3686 counts, so the sample rate is 1 kHz (TOUCH_STUCK_SAMPLES = one minute). */
#define TICK_RELOAD (65536u - 3686u)

/* ---- interrupt vector numbers (SDCC: vector address = 8 * n + 3) ----------------------- *
 * From the P89LPC938 user manual's interrupt table; the enable bits are IEN0/IEN1 in
 * p89lpc938.h (IEN1: EI2C bit 0, EKBI bit 1, in vector order).
 *   1  0x000B  Timer 0 (TF0)                   enable ET0
 *   6  0x0033  I2C serial interface (SI)       enable EI2C (IEN1.0)
 *   7  0x003B  keypad interrupt (KBIF)         enable EKBI (IEN1.1)
 * (14 0x0073 is the shared ADC / data-EEPROM vector: not used, both are polled.) */
#define VECTOR_TIMER0 1
#define VECTOR_I2C 6
#define VECTOR_KBI 7

/* ---- register bits not named in p89lpc938.h -------------------------------------------- */

/* AD0CON: ENBI0 7, ENADCI0 6, TMM0 5, EDGE0 4, ADCI0 3, ENADC0 2, ADCS01..00 1..0. */
#define AD0CON_ADCI0 0x08u
#define AD0CON_ENADC0 0x04u
#define AD0CON_START_IMMEDIATE 0x01u /* ADCS0 = 01: start a conversion now */
/* AD0MODA: BNDI0 7, BURST0 6, SCC0 5 (fixed channel, single conversion), SCAN0 4. */
#define AD0MODA_SCC0 0x20u
/* AD0MODB: CLK2..0 in 7..5, ADC clock = CCLK / (CLK + 1) <= 3.3 MHz: 7.373 / 3 = 2.46 MHz. */
#define AD0MODB_CLK_DIV3 0x40u
/* Fixed-channel single conversion puts channel n's result in AD0DATnL (bits 9..2) and
 * AD0DATnR (bits 1..0 in its low bits); the pairs sit at xdata 0xFFFF - 2n / 0xFFFE - 2n. */
#define HALL_DAT_L (*(__xdata volatile uint8_t *)(0xFFFFu - 2u * SEG_HALL_CHANNEL))
#define HALL_DAT_R (*(__xdata volatile uint8_t *)(0xFFFEu - 2u * SEG_HALL_CHANNEL))

/* KBCON: PATN_SEL 1 (0: interrupt while P0 & KBMASK != KBPATN), KBIF 0. */
#define KBCON_PATN_NOT_EQUAL 0x00u

/* DEECON: EEIF 7 (operation finished), HVERR 6, ECTL1..0 5..4 (00: byte), EWERR1..0, EADR8 0.
 * A byte operation starts when DEEADR is written: a read when DEEDAT was not written first,
 * a write of DEEDAT otherwise. */
#define DEECON_EEIF 0x80u
#define DEECON_BYTE_MODE 0x00u
#define EE_ADDRESS 0x00u    /* the assigned address */
#define EE_COMPLEMENT 0x01u /* its bitwise complement: an erased or torn store is ignored */

/* ---- state shared with the interrupt routines ------------------------------------------ */

static seg_target_t target;          /* the I2C target: the SI routine steps it, main publishes */
static volatile uint8_t touch_raw;   /* touch bits latched by the keypad interrupt */
static volatile uint8_t tick;        /* set by timer 0 once per sample period */
static volatile uint8_t store_pending; /* the SI routine moved to a new address */

static seg_debounce_t debounce;
static __xdata uint16_t samples[SEG_OVERSAMPLE_COUNT];

/* ---- data EEPROM ------------------------------------------------------------------------ */

static uint8_t eeprom_read(uint8_t ee_addr)
{
    DEECON = DEECON_BYTE_MODE; /* clears EEIF; EADR8 = 0 */
    DEEADR = ee_addr;          /* starts the read */
    while ((DEECON & DEECON_EEIF) == 0) {
    }
    return DEEDAT;
}

static void eeprom_write(uint8_t ee_addr, uint8_t value)
{
    DEECON = DEECON_BYTE_MODE;
    DEEDAT = value;
    DEEADR = ee_addr; /* starts the write (a few ms; the main loop skips those samples) */
    while ((DEECON & DEECON_EEIF) == 0) {
    }
}

/* Stores the new address. Called from the main loop only: an EEPROM write takes
 * milliseconds, far too long for the SI routine, which holds SCL low while it runs. */
static void store_address(uint8_t address)
{
    if (eeprom_read(EE_ADDRESS) != address) {
        eeprom_write(EE_ADDRESS, address);
    }
    if (eeprom_read(EE_COMPLEMENT) != (uint8_t)~address) {
        eeprom_write(EE_COMPLEMENT, (uint8_t)~address);
    }
}

/* ---- peripherals -------------------------------------------------------------------------- */

static uint8_t read_touch_pins(void)
{
    /* The four pins in one port read: one instant. Active low. */
    return (uint8_t)(~P0 & TOUCH_PINS_MASK);
}

static uint16_t adc_convert(void)
{
    uint8_t lo;
    uint8_t hi;
    AD0CON = AD0CON_ENADC0 | AD0CON_START_IMMEDIATE; /* clears ADCI0, starts */
    while ((AD0CON & AD0CON_ADCI0) == 0) {
    }
    lo = HALL_DAT_R;
    hi = HALL_DAT_L;
    return (uint16_t)(((uint16_t)hi << 2) | (lo & 0x03u));
}

static void hardware_init(uint8_t address)
{
    /* Touch pins: quasi-bidirectional (weak pull-up), the switches pull them low. */
    P0M1 &= (uint8_t)~TOUCH_PINS_MASK;
    P0M2 &= (uint8_t)~TOUCH_PINS_MASK;
    P0 |= TOUCH_PINS_MASK;

    /* ADC0: the Hall channel, fixed channel single conversion. The analog pin stays in its
     * reset state (input only); enable the converter early, it needs 10 us to settle. */
    AD0MODA = AD0MODA_SCC0;
    AD0MODB = AD0MODB_CLK_DIV3;
    AD0INS = (uint8_t)(1u << SEG_HALL_CHANNEL);
    AD0CON = AD0CON_ENADC0;

    /* I2C target: P1.2/P1.3 open drain; own address, no general call; I2EN and AA. */
    P1M1 |= 0x0Cu;
    P1M2 |= 0x0Cu;
    I2ADR = (uint8_t)(address << 1);
    I2CON = 0x44u; /* I2EN | AA, STA = STO = SI = 0, CRSEL = 0 */

    /* Keypad interrupt on KB0..KB3: fires when the pins differ from the last latched pattern. */
    touch_raw = read_touch_pins();
    KBPATN = (uint8_t)(~touch_raw & TOUCH_PINS_MASK);
    KBMASK = TOUCH_PINS_MASK;
    KBCON = KBCON_PATN_NOT_EQUAL;

    /* Timer 0: 16-bit timer, 1 ms tick. */
    TMOD = (uint8_t)((TMOD & 0xF0u) | 0x01u);
    TH0 = (uint8_t)(TICK_RELOAD >> 8);
    TL0 = (uint8_t)TICK_RELOAD;
    TR0 = 1;

    /* The I2C interrupt at the highest priority: SCL is held low until SI is cleared. */
    IP1 |= 0x01u; /* PI2C */
    IP1H |= 0x01u;
    ET0 = 1;
    EI2C = 1;
    EKBI = 1;
}

/* ---- interrupt routines ------------------------------------------------------------------- */

void timer0_isr(void) __interrupt(VECTOR_TIMER0)
{
    TH0 = (uint8_t)(TICK_RELOAD >> 8);
    TL0 = (uint8_t)TICK_RELOAD;
    tick = 1;
}

void keypad_isr(void) __interrupt(VECTOR_KBI)
{
    uint8_t pins = P0 & TOUCH_PINS_MASK; /* all four pins at one instant */
    KBPATN = pins;                       /* next interrupt on the next change */
    touch_raw = (uint8_t)(~pins & TOUCH_PINS_MASK);
    KBCON = KBCON_PATN_NOT_EQUAL; /* clears KBIF */
}

void i2c_isr(void) __interrupt(VECTOR_I2C)
{
    uint8_t stat = I2STAT;
    uint8_t tx;
    uint8_t flags = seg_target_step(&target, stat, I2DAT, &tx);

    /* Slave-transmitter states: load the byte to send. */
    if (stat == 0xA8u || stat == 0xB0u || stat == 0xB8u) {
        I2DAT = tx;
    }
    if ((flags & SEG_STEP_ADDRESS_CHANGED) != 0) {
        /* Takes effect at the next START; the EEPROM store waits for the main loop. */
        I2ADR = (uint8_t)(target.address << 1);
        store_pending = 1;
    }
    if (stat == 0x00u) {
        /* Bus error: setting STO in slave mode releases SDA/SCL and resets the I2C
         * hardware to not-addressed slave; no STOP is sent. STO clears itself. */
        STO = 1;
    }
    AA = (flags & SEG_STEP_ACK_NEXT) != 0;
    SI = 0;
}

/* ---- main loop ------------------------------------------------------------------------------ */

void main(void)
{
    uint8_t i;
    uint8_t status;
    uint8_t debounced;
    uint8_t address;
    uint16_t angle;
    uint16_t word;

    address = eeprom_read(EE_ADDRESS);
    if (eeprom_read(EE_COMPLEMENT) == (uint8_t)~address && address >= SEG_MIN_ADDRESS &&
        address <= SEG_MAX_ADDRESS) {
        seg_target_init(&target, address, 1);
    } else {
        seg_target_init(&target, SEG_DEFAULT_ADDRESS, 0);
    }
    seg_debounce_init(&debounce);
    hardware_init(target.address);
    EA = 1;

    for (;;) {
        while (tick == 0) {
        }
        tick = 0;

        for (i = 0; i < SEG_OVERSAMPLE_COUNT; i++) {
            samples[i] = adc_convert();
        }
        angle = seg_oversample(samples);
        status = seg_adc_fault(samples) != 0 ? SEG_STATUS_ADC_FAULT : 0u;
        debounced = seg_debounce_step(&debounce, touch_raw);
        if (seg_touch_stuck(&debounce) != 0) {
            status |= SEG_STATUS_TOUCH_STUCK;
        }
        word = seg_pack(angle, debounced);

        /* The SI routine reads and writes `target`: publish with interrupts off. */
        EA = 0;
        if (target.address_set == 0) {
            status |= SEG_STATUS_ADDRESS_NOT_SET;
        }
        seg_target_publish(&target, word, status);
        address = target.address;
        i = store_pending;
        store_pending = 0;
        EA = 1;

        if (i != 0) {
            store_address(address);
        }
    }
}
