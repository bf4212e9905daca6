// SPDX-License-Identifier: MIT
/* Runs an AVR test image under simavr (libsimavr) and reports what the
 * firmware does through three channels (targets/port/avr.cc):
 *   USART0 output      -> copied to stdout, byte for byte;
 *   writes to GPIOR1   -> the exact cycle count at each write, one line per
 *                         mark, to the file given with -o (measurements);
 *   a write to GPIOR2  -> the exit status; the run stops there.
 * Usage: fdsurf_simavr -m MCU [-f HZ] [-o MARKS] [-c MAX_CYCLES] IMAGE.elf
 * Exits with the firmware's status, or 124 when MAX_CYCLES pass first, or 125
 * when the core crashes or stops without a status. */
#include <avr_uart.h>
#include <sim_avr.h>
#include <sim_elf.h>
#include <sim_io.h>
#include <sim_irq.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

/* Data-space addresses of GPIOR1 and GPIOR2, the same on the ATmega328P and
 * the ATmega2560. */
enum { kMarkAddress = 0x4A, kExitAddress = 0x4B };

static FILE* g_marks;
static FILE* g_uart; /* the real stdout; simavr's own messages go to stderr */
static int g_exit_status = -1;

static void OnUartByte(struct avr_irq_t* irq, uint32_t value, void* param) {
  (void)irq;
  (void)param;
  fputc((int)(value & 0xFF), g_uart);
}

static void OnMark(struct avr_t* avr, avr_io_addr_t addr, uint8_t v, void* param) {
  (void)addr;
  (void)v;
  (void)param;
  if (g_marks != NULL) fprintf(g_marks, "%llu\n", (unsigned long long)avr->cycle);
}

static void OnExit(struct avr_t* avr, avr_io_addr_t addr, uint8_t v, void* param) {
  (void)avr;
  (void)addr;
  (void)param;
  g_exit_status = v;
}

int main(int argc, char** argv) {
  const char* mcu = NULL;
  const char* marks_path = NULL;
  unsigned long frequency = 16000000;
  unsigned long long max_cycles = 4000000000ull;
  int opt;
  while ((opt = getopt(argc, argv, "m:f:o:c:")) != -1) {
    switch (opt) {
      case 'm':
        mcu = optarg;
        break;
      case 'f':
        frequency = strtoul(optarg, NULL, 10);
        break;
      case 'o':
        marks_path = optarg;
        break;
      case 'c':
        max_cycles = strtoull(optarg, NULL, 10);
        break;
      default:
        return 2;
    }
  }
  if (mcu == NULL || optind + 1 != argc) {
    fprintf(stderr, "usage: fdsurf_simavr -m MCU [-f HZ] [-o MARKS] [-c MAX_CYCLES] IMAGE.elf\n");
    return 2;
  }
  /* libsimavr prints progress ("Loaded ... .text") on stdout: keep stdout for
   * the UART and send everything else to stderr. */
  fflush(stdout);
  g_uart = fdopen(dup(STDOUT_FILENO), "w");
  if (g_uart == NULL || dup2(STDERR_FILENO, STDOUT_FILENO) < 0) {
    perror("fdsurf_simavr");
    return 2;
  }
  elf_firmware_t firmware;
  memset(&firmware, 0, sizeof firmware);
  if (elf_read_firmware(argv[optind], &firmware) != 0) {
    fprintf(stderr, "fdsurf_simavr: cannot read %s\n", argv[optind]);
    return 2;
  }
  avr_t* avr = avr_make_mcu_by_name(mcu);
  if (avr == NULL) {
    fprintf(stderr, "fdsurf_simavr: unknown MCU %s\n", mcu);
    return 2;
  }
  avr_init(avr);
  avr->log = LOG_ERROR;
  firmware.frequency = (uint32_t)frequency;
  avr_load_firmware(avr, &firmware);
  avr->frequency = (uint32_t)frequency;

  /* No console echo and no real-time sleeping while the firmware polls. */
  uint32_t flags = 0;
  avr_ioctl(avr, AVR_IOCTL_UART_SET_FLAGS('0'), &flags);
  avr_irq_register_notify(avr_io_getirq(avr, AVR_IOCTL_UART_GETIRQ('0'), UART_IRQ_OUTPUT),
                          OnUartByte, NULL);
  if (marks_path != NULL && (g_marks = fopen(marks_path, "w")) == NULL) {
    perror(marks_path);
    return 2;
  }
  avr_register_io_write(avr, kMarkAddress, OnMark, NULL);
  avr_register_io_write(avr, kExitAddress, OnExit, NULL);

  int state = cpu_Running;
  while (g_exit_status < 0 && avr->cycle < max_cycles) {
    state = avr_run(avr);
    if (state == cpu_Done || state == cpu_Crashed) break;
  }
  fclose(g_uart);
  if (g_marks != NULL) fclose(g_marks);
  fprintf(stderr, "fdsurf_simavr: %s, %llu cycles\n", mcu, (unsigned long long)avr->cycle);
  if (g_exit_status >= 0) return g_exit_status;
  return avr->cycle >= max_cycles ? 124 : 125;
}
