// SPDX-License-Identifier: MIT
/* A QEMU TCG plugin for the micro:bit harness (run_qemu.py): emulated time
 * for the GPIO trace events, and a clock the harness can read.
 *
 * QEMU's nrf51_gpio_* trace events say which pin changed to which level but
 * not when in guest time (the log backend stamps them, if at all, with the
 * host's wall clock). Under -icount the guest's time is its instruction
 * count times 2^shift ns, so this plugin:
 *   - counts executed instructions (an inline add before each instruction)
 *     in a 64-bit word of a file the harness maps too (`clock=FILE`), which
 *     is the harness's view of emulated time for pacing UART bytes;
 *   - after every guest store into the GPIO block (0x50000000..0x50000FFF)
 *     writes "T <count>" to the QEMU log, where the store's own
 *     nrf51_gpio_update_output_irq lines precede it (same thread, same log):
 *     the harness stamps those pin changes with that count, the store's own
 *     (its add has run).
 *
 * Per instruction, not one add per translation block: under -icount a
 * device access in the middle of a block stops the block there and runs the
 * access again as the last instruction of a new one; a per-block add had
 * counted the whole block already, so the count ran ahead of QEMU's
 * virtual clock (by 15 % over a CI job, 50 % in the idle main loop, which
 * polls the timer: 17 400 step ticks per count-second, not 20 000). The
 * re-run instruction is translated with memory callbacks only, so per-
 * instruction adds count each instruction once: 20 000 ticks a second.
 *
 * Debian's QEMU 7.2 ships no qemu-plugin.h: the API-v1 declarations used
 * are written out below from the plugin API documentation.
 *
 * Usage: -plugin libfdsurf_microbit_pins.so,clock=FILE -d plugin -D LOG */
#include <fcntl.h>
#include <inttypes.h>
#include <stdint.h>
#include <stdio.h>
#include <string.h>
#include <sys/mman.h>
#include <unistd.h>

/* --- The part of qemu-plugin.h (API version 1) this plugin uses. --- */
typedef uint64_t qemu_plugin_id_t;
typedef struct qemu_info_t qemu_info_t;
typedef uint32_t qemu_plugin_meminfo_t;
struct qemu_plugin_tb;
struct qemu_plugin_insn;
enum qemu_plugin_cb_flags { QEMU_PLUGIN_CB_NO_REGS, QEMU_PLUGIN_CB_R_REGS, QEMU_PLUGIN_CB_RW_REGS };
enum qemu_plugin_mem_rw { QEMU_PLUGIN_MEM_R = 1, QEMU_PLUGIN_MEM_W, QEMU_PLUGIN_MEM_RW };
enum qemu_plugin_op { QEMU_PLUGIN_INLINE_ADD_U64 };
typedef void (*qemu_plugin_vcpu_tb_trans_cb_t)(qemu_plugin_id_t id, struct qemu_plugin_tb* tb);
typedef void (*qemu_plugin_vcpu_mem_cb_t)(unsigned int vcpu_index, qemu_plugin_meminfo_t info,
                                          uint64_t vaddr, void* userdata);
typedef void (*qemu_plugin_udata_cb_t)(qemu_plugin_id_t id, void* userdata);
void qemu_plugin_register_vcpu_tb_trans_cb(qemu_plugin_id_t id, qemu_plugin_vcpu_tb_trans_cb_t cb);
size_t qemu_plugin_tb_n_insns(const struct qemu_plugin_tb* tb);
struct qemu_plugin_insn* qemu_plugin_tb_get_insn(const struct qemu_plugin_tb* tb, size_t idx);
void qemu_plugin_register_vcpu_insn_exec_inline(struct qemu_plugin_insn* insn,
                                                enum qemu_plugin_op op, void* ptr, uint64_t imm);
void qemu_plugin_register_vcpu_mem_cb(struct qemu_plugin_insn* insn, qemu_plugin_vcpu_mem_cb_t cb,
                                      enum qemu_plugin_cb_flags flags, enum qemu_plugin_mem_rw rw,
                                      void* userdata);
void qemu_plugin_register_atexit_cb(qemu_plugin_id_t id, qemu_plugin_udata_cb_t cb, void* userdata);
void qemu_plugin_outs(const char* string);
#define QEMU_PLUGIN_EXPORT __attribute__((visibility("default")))
/* --- end of the declarations --- */

QEMU_PLUGIN_EXPORT int qemu_plugin_version = 1;

enum { kGpioBase = 0x50000000u, kGpioSize = 0x1000u };

static uint64_t g_private_count;                      /* until the clock file is mapped */
static volatile uint64_t* g_count = &g_private_count; /* one vCPU (nRF51) */

static void OnStore(unsigned int vcpu_index, qemu_plugin_meminfo_t info, uint64_t vaddr,
                    void* userdata) {
  (void)vcpu_index;
  (void)info;
  if (vaddr - kGpioBase >= kGpioSize) return;
  char line[40];
  (void)userdata;
  snprintf(line, sizeof line, "T %" PRIu64 "\n", *g_count);
  qemu_plugin_outs(line);
}

static void OnTranslate(qemu_plugin_id_t id, struct qemu_plugin_tb* tb) {
  (void)id;
  const size_t n = qemu_plugin_tb_n_insns(tb);
  for (size_t i = 0; i < n; ++i) {
    struct qemu_plugin_insn* insn = qemu_plugin_tb_get_insn(tb, i);
    qemu_plugin_register_vcpu_insn_exec_inline(insn, QEMU_PLUGIN_INLINE_ADD_U64, (void*)g_count, 1);
    qemu_plugin_register_vcpu_mem_cb(insn, OnStore, QEMU_PLUGIN_CB_NO_REGS, QEMU_PLUGIN_MEM_W,
                                     NULL);
  }
}

static void OnExit(qemu_plugin_id_t id, void* userdata) {
  (void)id;
  (void)userdata;
  char line[48];
  snprintf(line, sizeof line, "END %" PRIu64 "\n", *g_count);
  qemu_plugin_outs(line);
}

QEMU_PLUGIN_EXPORT int qemu_plugin_install(qemu_plugin_id_t id, const qemu_info_t* info, int argc,
                                           char** argv) {
  (void)info;
  for (int i = 0; i < argc; ++i) {
    if (strncmp(argv[i], "clock=", 6) != 0) {
      qemu_plugin_outs("fdsurf microbit plugin: unknown argument (clock=FILE)\n");
      return -1;
    }
    const int fd = open(argv[i] + 6, O_RDWR);
    if (fd < 0 || ftruncate(fd, 4096) != 0) return -1;
    void* map = mmap(NULL, 4096, PROT_READ | PROT_WRITE, MAP_SHARED, fd, 0);
    close(fd);
    if (map == MAP_FAILED) return -1;
    g_count = (volatile uint64_t*)map;
    *g_count = 0;
  }
  qemu_plugin_register_vcpu_tb_trans_cb(id, OnTranslate);
  qemu_plugin_register_atexit_cb(id, OnExit, NULL);
  return 0;
}
