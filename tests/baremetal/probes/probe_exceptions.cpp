// Negative control of the no-exception-tables promise, compiled with -fexceptions: a handler
// around a call that may throw leaves an unwind table entry, a catch table and a personality
// routine (test link.no_exceptions_rtti). Checked as an object: linked, it would also drag in
// libsupc++'s abort path and thread-local exception globals, which the board refuses to link.
int may_throw(int v);  // defined nowhere: the object is never linked

int main() {
  try {
    return may_throw(-1);
  } catch (...) {
    return 1;
  }
}
