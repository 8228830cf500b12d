/* The part of QEMU's TCG plugin API that icount_plugin.c uses, declared here because Debian
 * ships no qemu-plugin.h. Written from QEMU's documented plugin API, version 1
 * (QEMU_PLUGIN_VERSION 1, the version of qemu-plugin.h in QEMU 7.2's sources). Checked
 * against Debian 12's qemu-aarch64 7.2: it exports every qemu_plugin_* function declared
 * below and refuses a plugin whose `qemu_plugin_version` lies outside its [min, cur] range,
 * so a QEMU that dropped version 1 says so at load time instead of misbehaving.
 *
 * Types and signatures must match QEMU's exactly: they are an ABI. */
#ifndef CCMAP_QEMU_PLUGIN_API_H
#define CCMAP_QEMU_PLUGIN_API_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#define CCMAP_QEMU_PLUGIN_API_VERSION 1

#define CCMAP_QEMU_PLUGIN_EXPORT __attribute__((visibility("default")))

typedef uint64_t qemu_plugin_id_t;

/* Passed to qemu_plugin_install; valid only during that call. */
typedef struct qemu_info_t {
  const char *target_name; /* guest architecture, "aarch64" for qemu-aarch64 */
  struct {
    int min;
    int cur;
  } version; /* plugin API versions this QEMU supports */
  bool system_emulation;
  union {
    struct {
      int smp_vcpus;
      int max_vcpus;
    } system;
  };
} qemu_info_t;

struct qemu_plugin_tb;   /* opaque: a translation block, valid during the translation callback */
struct qemu_plugin_insn; /* opaque: one guest instruction of that block */

enum qemu_plugin_cb_flags {
  QEMU_PLUGIN_CB_NO_REGS,
  QEMU_PLUGIN_CB_R_REGS,
  QEMU_PLUGIN_CB_RW_REGS,
};

enum qemu_plugin_op {
  QEMU_PLUGIN_INLINE_ADD_U64,
};

typedef void (*qemu_plugin_udata_cb_t)(qemu_plugin_id_t id, void *userdata);
typedef void (*qemu_plugin_vcpu_simple_cb_t)(qemu_plugin_id_t id, unsigned int vcpu_index);
typedef void (*qemu_plugin_vcpu_udata_cb_t)(unsigned int vcpu_index, void *userdata);
typedef void (*qemu_plugin_vcpu_tb_trans_cb_t)(qemu_plugin_id_t id, struct qemu_plugin_tb *tb);

/* Defined by the plugin. */
extern CCMAP_QEMU_PLUGIN_EXPORT int qemu_plugin_version;
CCMAP_QEMU_PLUGIN_EXPORT int qemu_plugin_install(qemu_plugin_id_t id, const qemu_info_t *info, int argc,
                                                 char **argv);

/* Provided by QEMU. */
void qemu_plugin_register_vcpu_init_cb(qemu_plugin_id_t id, qemu_plugin_vcpu_simple_cb_t cb);
void qemu_plugin_register_vcpu_tb_trans_cb(qemu_plugin_id_t id, qemu_plugin_vcpu_tb_trans_cb_t cb);
void qemu_plugin_register_atexit_cb(qemu_plugin_id_t id, qemu_plugin_udata_cb_t cb, void *userdata);
/* Runs cb before the instruction executes, every time it executes. */
void qemu_plugin_register_vcpu_insn_exec_cb(struct qemu_plugin_insn *insn, qemu_plugin_vcpu_udata_cb_t cb,
                                            enum qemu_plugin_cb_flags flags, void *userdata);
/* Adds imm to *ptr (translated code, no call) before the instruction executes; not atomic. */
void qemu_plugin_register_vcpu_insn_exec_inline(struct qemu_plugin_insn *insn, enum qemu_plugin_op op, void *ptr,
                                                uint64_t imm);
size_t qemu_plugin_tb_n_insns(const struct qemu_plugin_tb *tb);
struct qemu_plugin_insn *qemu_plugin_tb_get_insn(const struct qemu_plugin_tb *tb, size_t idx);
const void *qemu_plugin_insn_data(const struct qemu_plugin_insn *insn);
size_t qemu_plugin_insn_size(const struct qemu_plugin_insn *insn);
uint64_t qemu_plugin_insn_vaddr(const struct qemu_plugin_insn *insn);
/* Writes to QEMU's log: shown with -d plugin (or -D FILE -d plugin). */
void qemu_plugin_outs(const char *string);

#endif /* CCMAP_QEMU_PLUGIN_API_H */
