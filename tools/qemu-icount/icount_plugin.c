/* libccmap_icount.so: a QEMU TCG plugin (user mode, aarch64 guests) that counts the guest
 * instructions executed between marker instructions (icount_marker_encoding.h), per region
 * and per instruction class (a64_class.h), and writes them to a file at exit.
 *
 *   qemu-aarch64 -L /usr/aarch64-linux-gnu -plugin libccmap_icount.so,out=FILE[,pcs=PCS] prog args
 *   (add -d plugin to see the same lines on QEMU's log)
 *
 * How it counts. At translation time each block is cut at its marker instructions into
 * segments; every segment's instruction and class counts are added by inline TCG adds (no
 * call) to running totals, before the segment's first instruction executes; each marker gets
 * a callback that, before the marker executes, snapshots the running totals (begin) or adds
 * their difference to the region (end). Control enters a block only at its top and leaves it
 * only at its end, so a segment that starts also runs to its end, and the counts are exact to
 * the instruction: the instructions executed between a begin and its end marker, every marker
 * instruction excluded (markers are counted in the total only). One limit: an instruction that
 * faults (a signal delivered to the guest) leaves the rest of its segment counted although it
 * did not run (a counted region should not fault anyway).
 *
 * Output (FILE), one line per region that saw a marker, then the total:
 *   region=<id> intervals=N insns=N fp=N simd_int=N simd_fp=N ldst=N min_interval_insns=N
 *     max_interval_insns=N unmatched=N
 *   total insns=N fp=N simd_int=N simd_fp=N ldst=N marker_errors=N vcpus=N
 * unmatched counts a begin of an open region, an end of a region that is not open, and a
 * region still open at exit; marker_errors is their sum over the regions (plus failed region
 * allocations). The counters are plain (not atomic) and the marker state is global: a guest
 * with more than one thread (vcpus > 1) gets meaningless counts, which is why vcpus is
 * reported. Only the process that loaded the plugin writes FILE (a forked child's counts are
 * dropped).
 *
 * Per-address mode (optional, a profiler on the target's count): pcs=PCS adds one inline add
 * per executed instruction (QEMU runs about twice as slow) and writes PCS at exit, sorted by
 * address:
 *   # ccmap icount per-address counts: guest virtual address, executions
 *   0x<address> <executions>          (one line per instruction that ran)
 *   # addresses=N dropped=N
 * Addresses are the guest's virtual ones (a PIE program sits at QEMU's load address;
 * tools/icount-annotate maps them to functions). The table holds 2^20 addresses; instructions
 * at addresses past that are not counted there, and `dropped` counts their translations. The
 * counts of PCS sum to the total's insns. */
#define _POSIX_C_SOURCE 200809L /* getpid, pid_t */

#include <errno.h>
#include <inttypes.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "a64_class.h"
#include "icount_marker_encoding.h"
#include "qemu_plugin_api.h"

CCMAP_QEMU_PLUGIN_EXPORT int qemu_plugin_version = CCMAP_QEMU_PLUGIN_API_VERSION;

/* Counter slots: 0 = all instructions, then one per a64_class except OTHER. */
enum { SLOT_INSNS, SLOT_FP, SLOT_SIMD_INT, SLOT_SIMD_FP, SLOT_LDST, SLOT_COUNT };
static const char *const kSlotNames[SLOT_COUNT] = {"insns", "fp", "simd_int", "simd_fp", "ldst"};

static int slot_of_class(enum a64_class c) {
  switch (c) {
    case A64_CLASS_FP:
      return SLOT_FP;
    case A64_CLASS_SIMD_INT:
      return SLOT_SIMD_INT;
    case A64_CLASS_SIMD_FP:
      return SLOT_SIMD_FP;
    case A64_CLASS_LDST:
      return SLOT_LDST;
    default:
      return -1;
  }
}

struct region {
  uint64_t counts[SLOT_COUNT];
  uint64_t snapshot[SLOT_COUNT]; /* running totals at the open interval's begin marker */
  uint64_t intervals;
  uint64_t min_interval_insns;
  uint64_t max_interval_insns;
  uint64_t unmatched;
  int open;
};

/* Running totals of the non-marker instructions since the program started: the inline adds
 * target this array. */
static uint64_t g_running[SLOT_COUNT];
static uint64_t g_markers; /* marker instructions executed */
/* Regions by id, allocated at their first marker (at most 65536). */
static struct region *g_regions[CCMAP_ICOUNT_MAX_REGION_ID + 1U];
static uint64_t g_vcpus;
static uint64_t g_alloc_failures;
static char *g_out_path;
static pid_t g_owner_pid;

/* Per-address mode: an open-addressing table of instruction addresses and their executions,
 * allocated only when pcs= is given. Address 0 marks a free entry (no guest code runs there). */
#define PCS_CAPACITY (1U << 20)
struct pc_count {
  uint64_t address;
  uint64_t executions;
};
static struct pc_count *g_pcs;
static size_t g_pcs_used;
static uint64_t g_pcs_dropped;
static char *g_pcs_path;

/* The table's entry of an address, created on first use; NULL when the table is full. */
static struct pc_count *pc_entry(uint64_t address) {
  size_t i = (size_t)(((address >> 2) * 0x9E3779B97F4A7C15ULL) >> 44); /* 20 bits */
  for (size_t probes = 0; probes < PCS_CAPACITY; ++probes, i = (i + 1U) & (PCS_CAPACITY - 1U)) {
    if (g_pcs[i].address == address) {
      return &g_pcs[i];
    }
    if (g_pcs[i].address == 0U) {
      if (g_pcs_used + 1U >= PCS_CAPACITY) {
        return NULL; /* keep one entry free: a lookup always ends */
      }
      g_pcs[i].address = address;
      ++g_pcs_used;
      return &g_pcs[i];
    }
  }
  return NULL;
}

/* Adds one execution of insn to its address's count (per-address mode). */
static void count_address(struct qemu_plugin_insn *insn) {
  if (g_pcs == NULL) {
    return;
  }
  struct pc_count *entry = pc_entry(qemu_plugin_insn_vaddr(insn));
  if (entry == NULL) {
    ++g_pcs_dropped;
    return;
  }
  qemu_plugin_register_vcpu_insn_exec_inline(insn, QEMU_PLUGIN_INLINE_ADD_U64, &entry->executions, 1U);
}

/* A marker's callback data: the region id and, in bit 16, end (1) or begin (0). */
#define MARKER_END_FLAG 0x10000U

static struct region *region_of(uint32_t id) {
  if (g_regions[id] == NULL) {
    g_regions[id] = calloc(1, sizeof(struct region));
    if (g_regions[id] == NULL) {
      ++g_alloc_failures;
    }
  }
  return g_regions[id];
}

static void on_marker(unsigned int vcpu_index, void *userdata) {
  (void)vcpu_index;
  const uintptr_t data = (uintptr_t)userdata;
  struct region *r = region_of((uint32_t)(data & CCMAP_ICOUNT_MAX_REGION_ID));
  ++g_markers;
  if (r == NULL) {
    return; /* counted in g_alloc_failures, reported as a marker error */
  }
  const int is_end = (data & MARKER_END_FLAG) != 0U;
  if (is_end != r->open) {
    ++r->unmatched; /* begin of an open region (the first begin stands) or end of a closed one */
    return;
  }
  if (!is_end) {
    memcpy(r->snapshot, g_running, sizeof g_running);
    r->open = 1;
    return;
  }
  const uint64_t insns = g_running[SLOT_INSNS] - r->snapshot[SLOT_INSNS];
  for (int s = 0; s < SLOT_COUNT; ++s) {
    r->counts[s] += g_running[s] - r->snapshot[s];
  }
  if (r->intervals == 0U || insns < r->min_interval_insns) {
    r->min_interval_insns = insns;
  }
  if (insns > r->max_interval_insns) {
    r->max_interval_insns = insns;
  }
  ++r->intervals;
  r->open = 0;
}

/* Adds one segment's counts, before its first instruction executes. */
static void instrument_segment(struct qemu_plugin_insn *first, const uint64_t counts[SLOT_COUNT]) {
  for (int s = 0; s < SLOT_COUNT; ++s) {
    if (counts[s] != 0U) {
      qemu_plugin_register_vcpu_insn_exec_inline(first, QEMU_PLUGIN_INLINE_ADD_U64, &g_running[s], counts[s]);
    }
  }
}

static void on_translate(qemu_plugin_id_t id, struct qemu_plugin_tb *tb) {
  (void)id;
  const size_t n = qemu_plugin_tb_n_insns(tb);
  uint64_t segment[SLOT_COUNT] = {0};
  struct qemu_plugin_insn *segment_first = NULL;
  for (size_t i = 0; i < n; ++i) {
    struct qemu_plugin_insn *insn = qemu_plugin_tb_get_insn(tb, i);
    count_address(insn);
    uint32_t word = 0;
    if (qemu_plugin_insn_size(insn) == sizeof word) {
      memcpy(&word, qemu_plugin_insn_data(insn), sizeof word); /* A64: 4 bytes, little-endian */
    }
    uint32_t region_id = 0;
    const int marker = a64_marker(word, &region_id);
    if (marker != 0) {
      if (segment_first != NULL) {
        instrument_segment(segment_first, segment);
      }
      memset(segment, 0, sizeof segment);
      segment_first = NULL;
      const uintptr_t data = region_id | (marker == 2 ? MARKER_END_FLAG : 0U);
      qemu_plugin_register_vcpu_insn_exec_cb(insn, on_marker, QEMU_PLUGIN_CB_NO_REGS, (void *)data);
      continue;
    }
    if (segment_first == NULL) {
      segment_first = insn;
    }
    ++segment[SLOT_INSNS];
    const int slot = slot_of_class(a64_classify(word));
    if (slot >= 0) {
      ++segment[slot];
    }
  }
  if (segment_first != NULL) {
    instrument_segment(segment_first, segment);
  }
}

static void on_vcpu_init(qemu_plugin_id_t id, unsigned int vcpu_index) {
  (void)id;
  (void)vcpu_index;
  ++g_vcpus;
}

static void emit(FILE *out, const char *line) {
  if (out != NULL) {
    fputs(line, out);
  }
  qemu_plugin_outs(line);
}

static int by_address(const void *a, const void *b) {
  const uint64_t x = ((const struct pc_count *)a)->address;
  const uint64_t y = ((const struct pc_count *)b)->address;
  return (x > y) - (x < y);
}

/* Writes the per-address counts (pcs=), sorted by address; the table is compacted in place. */
static void write_pcs(void) {
  size_t n = 0;
  for (size_t i = 0; i < PCS_CAPACITY; ++i) {
    if (g_pcs[i].address != 0U && g_pcs[i].executions != 0U) {
      g_pcs[n++] = g_pcs[i];
    }
  }
  qsort(g_pcs, n, sizeof *g_pcs, by_address);
  FILE *out = fopen(g_pcs_path, "w");
  if (out == NULL) {
    fprintf(stderr, "ccmap icount: cannot write %s: %s\n", g_pcs_path, strerror(errno));
    return;
  }
  fputs("# ccmap icount per-address counts: guest virtual address, executions\n", out);
  for (size_t i = 0; i < n; ++i) {
    fprintf(out, "0x%" PRIx64 " %" PRIu64 "\n", g_pcs[i].address, g_pcs[i].executions);
  }
  fprintf(out, "# addresses=%zu dropped=%" PRIu64 "\n", n, g_pcs_dropped);
  if (fclose(out) != 0) {
    fprintf(stderr, "ccmap icount: cannot write %s: %s\n", g_pcs_path, strerror(errno));
  }
}

static void on_exit_write(qemu_plugin_id_t id, void *userdata) {
  (void)id;
  (void)userdata;
  if (getpid() != g_owner_pid) {
    return; /* a forked child: only the process that loaded the plugin writes the file */
  }
  if (g_pcs != NULL) {
    write_pcs();
  }
  FILE *out = fopen(g_out_path, "w");
  if (out == NULL) {
    fprintf(stderr, "ccmap icount: cannot write %s: %s\n", g_out_path, strerror(errno));
  }
  char line[512];
  uint64_t errors = g_alloc_failures;
  for (uint32_t rid = 0; rid <= CCMAP_ICOUNT_MAX_REGION_ID; ++rid) {
    struct region *r = g_regions[rid];
    if (r == NULL) {
      continue;
    }
    if (r->open) {
      ++r->unmatched; /* never ended */
    }
    errors += r->unmatched;
    int len = snprintf(line, sizeof line, "region=%" PRIu32 " intervals=%" PRIu64, rid, r->intervals);
    for (int s = 0; s < SLOT_COUNT; ++s) {
      len += snprintf(line + len, sizeof line - (size_t)len, " %s=%" PRIu64, kSlotNames[s], r->counts[s]);
    }
    snprintf(line + len, sizeof line - (size_t)len,
             " min_interval_insns=%" PRIu64 " max_interval_insns=%" PRIu64 " unmatched=%" PRIu64 "\n",
             r->min_interval_insns, r->max_interval_insns, r->unmatched);
    emit(out, line);
  }
  int len = snprintf(line, sizeof line, "total");
  for (int s = 0; s < SLOT_COUNT; ++s) {
    const uint64_t value = g_running[s] + (s == SLOT_INSNS ? g_markers : 0U);
    len += snprintf(line + len, sizeof line - (size_t)len, " %s=%" PRIu64, kSlotNames[s], value);
  }
  snprintf(line + len, sizeof line - (size_t)len, " marker_errors=%" PRIu64 " vcpus=%" PRIu64 "\n", errors, g_vcpus);
  emit(out, line);
  if (out != NULL && fclose(out) != 0) {
    fprintf(stderr, "ccmap icount: cannot write %s: %s\n", g_out_path, strerror(errno));
  }
}

CCMAP_QEMU_PLUGIN_EXPORT int qemu_plugin_install(qemu_plugin_id_t id, const qemu_info_t *info, int argc,
                                                 char **argv) {
  if (info->system_emulation || strcmp(info->target_name, "aarch64") != 0) {
    fprintf(stderr, "ccmap icount: needs qemu-aarch64 user mode (got %s, %s emulation)\n", info->target_name,
            info->system_emulation ? "system" : "user");
    return -1;
  }
  for (int i = 0; i < argc; ++i) {
    if (strncmp(argv[i], "out=", 4) == 0 && argv[i][4] != '\0') {
      g_out_path = argv[i] + 4; /* argv stays valid for the plugin's lifetime */
    } else if (strncmp(argv[i], "pcs=", 4) == 0 && argv[i][4] != '\0') {
      g_pcs_path = argv[i] + 4;
    } else {
      fprintf(stderr, "ccmap icount: unknown argument '%s' (expected out=FILE [pcs=FILE])\n", argv[i]);
      return -1;
    }
  }
  if (g_pcs_path != NULL) {
    g_pcs = calloc(PCS_CAPACITY, sizeof *g_pcs);
    if (g_pcs == NULL) {
      fprintf(stderr, "ccmap icount: no memory for the per-address table\n");
      return -1;
    }
    FILE *pcs = fopen(g_pcs_path, "w"); /* truncated now, as FILE */
    if (pcs == NULL) {
      fprintf(stderr, "ccmap icount: cannot write %s: %s\n", g_pcs_path, strerror(errno));
      return -1;
    }
    fclose(pcs);
  }
  if (g_out_path == NULL) {
    fprintf(stderr, "ccmap icount: missing argument out=FILE\n");
    return -1;
  }
  /* Truncate now: a run that dies before exit leaves no stale counts behind. */
  FILE *out = fopen(g_out_path, "w");
  if (out == NULL) {
    fprintf(stderr, "ccmap icount: cannot write %s: %s\n", g_out_path, strerror(errno));
    return -1;
  }
  fclose(out);
  g_owner_pid = getpid();
  qemu_plugin_register_vcpu_init_cb(id, on_vcpu_init);
  qemu_plugin_register_vcpu_tb_trans_cb(id, on_translate);
  qemu_plugin_register_atexit_cb(id, on_exit_write, NULL);
  return 0;
}
