// SPDX-License-Identifier: MIT
/* A QEMU TCG plugin that counts executed guest instructions and records the
 * count each time the guest reaches a marker address (the image's
 * fdsurf_image_mark, targets/port/). The cost of a measured loop is the
 * difference between the two marks around it.
 *
 * Debian's QEMU 7.2 loads plugins (-plugin) but ships no qemu-plugin.h, so the
 * few API-v1 declarations used here are written out below, from the plugin
 * API documentation.
 *
 * Usage: -plugin libfdsurf_qemu_insn.so,mark=0xADDRESS,out=FILE
 * FILE gets one line per mark: the number of instructions executed so far.
 * Counting is per translation block, at block entry: the count at a mark
 * includes the marker's own block, the same offset at both ends of a loop. */
#include <inttypes.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* --- The part of qemu-plugin.h (API version 1) this plugin uses. --- */
typedef uint64_t qemu_plugin_id_t;
typedef struct qemu_info_t qemu_info_t;
struct qemu_plugin_tb;
struct qemu_plugin_insn;
enum qemu_plugin_cb_flags { QEMU_PLUGIN_CB_NO_REGS, QEMU_PLUGIN_CB_R_REGS, QEMU_PLUGIN_CB_RW_REGS };
enum qemu_plugin_op { QEMU_PLUGIN_INLINE_ADD_U64 };
typedef void (*qemu_plugin_vcpu_tb_trans_cb_t)(qemu_plugin_id_t id, struct qemu_plugin_tb* tb);
typedef void (*qemu_plugin_vcpu_udata_cb_t)(unsigned int vcpu_index, void* userdata);
typedef void (*qemu_plugin_udata_cb_t)(qemu_plugin_id_t id, void* userdata);
void qemu_plugin_register_vcpu_tb_trans_cb(qemu_plugin_id_t id, qemu_plugin_vcpu_tb_trans_cb_t cb);
size_t qemu_plugin_tb_n_insns(const struct qemu_plugin_tb* tb);
struct qemu_plugin_insn* qemu_plugin_tb_get_insn(const struct qemu_plugin_tb* tb, size_t idx);
uint64_t qemu_plugin_insn_vaddr(const struct qemu_plugin_insn* insn);
void qemu_plugin_register_vcpu_tb_exec_inline(struct qemu_plugin_tb* tb, enum qemu_plugin_op op,
                                              void* ptr, uint64_t imm);
void qemu_plugin_register_vcpu_insn_exec_cb(struct qemu_plugin_insn* insn,
                                            qemu_plugin_vcpu_udata_cb_t cb,
                                            enum qemu_plugin_cb_flags flags, void* userdata);
void qemu_plugin_register_atexit_cb(qemu_plugin_id_t id, qemu_plugin_udata_cb_t cb, void* userdata);
void qemu_plugin_outs(const char* string);
#define QEMU_PLUGIN_EXPORT __attribute__((visibility("default")))
/* --- end of the declarations --- */

QEMU_PLUGIN_EXPORT int qemu_plugin_version = 1;

static uint64_t g_instructions; /* one vCPU: the boards used are single-core */
static uint64_t g_mark_address;
static FILE* g_out;

static void OnMark(unsigned int vcpu_index, void* userdata) {
  (void)vcpu_index;
  (void)userdata;
  if (g_out != NULL) {
    fprintf(g_out, "%" PRIu64 "\n", g_instructions);
    fflush(g_out);
  }
}

static void OnTranslate(qemu_plugin_id_t id, struct qemu_plugin_tb* tb) {
  (void)id;
  const size_t n = qemu_plugin_tb_n_insns(tb);
  qemu_plugin_register_vcpu_tb_exec_inline(tb, QEMU_PLUGIN_INLINE_ADD_U64, &g_instructions, n);
  for (size_t i = 0; i < n; ++i) {
    struct qemu_plugin_insn* insn = qemu_plugin_tb_get_insn(tb, i);
    if (qemu_plugin_insn_vaddr(insn) == g_mark_address) {
      qemu_plugin_register_vcpu_insn_exec_cb(insn, OnMark, QEMU_PLUGIN_CB_NO_REGS, NULL);
    }
  }
}

static void OnExit(qemu_plugin_id_t id, void* userdata) {
  (void)id;
  (void)userdata;
  if (g_out != NULL) {
    fprintf(g_out, "total %" PRIu64 "\n", g_instructions);
    fclose(g_out);
    g_out = NULL;
  }
}

QEMU_PLUGIN_EXPORT int qemu_plugin_install(qemu_plugin_id_t id, const qemu_info_t* info, int argc,
                                           char** argv) {
  (void)info;
  const char* out = NULL;
  for (int i = 0; i < argc; ++i) {
    if (strncmp(argv[i], "mark=", 5) == 0) {
      g_mark_address = strtoull(argv[i] + 5, NULL, 0) & ~(uint64_t)1; /* Thumb bit */
    } else if (strncmp(argv[i], "out=", 4) == 0) {
      out = argv[i] + 4;
    } else {
      qemu_plugin_outs("fdsurf insn plugin: unknown argument\n");
      return -1;
    }
  }
  if (out == NULL || g_mark_address == 0) {
    qemu_plugin_outs("fdsurf insn plugin: needs mark=ADDRESS,out=FILE\n");
    return -1;
  }
  g_out = fopen(out, "w");
  if (g_out == NULL) return -1;
  qemu_plugin_register_vcpu_tb_trans_cb(id, OnTranslate);
  qemu_plugin_register_atexit_cb(id, OnExit, NULL);
  return 0;
}
