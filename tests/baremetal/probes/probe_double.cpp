// Negative control of the no-soft-double promise: double arithmetic, which the Cortex-M7's
// single-precision FPU leaves to libgcc's __aeabi_d* helpers (test link.no_soft_double).
volatile double g_value = 1.5;

int main() {
  g_value = g_value * 3.0 + 0.5;
  return g_value > 4.0 ? 0 : 1;
}
