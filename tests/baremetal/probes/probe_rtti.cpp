// Negative control of the no-RTTI promise, compiled with -frtti: typeid of a polymorphic class
// emits type_info objects (_ZTI/_ZTS symbols; test link.no_exceptions_rtti). Checked as an
// object: linked, libsupc++'s type_info classes would also bring operator delete and the heap.
#include <typeinfo>

struct Shape {
  virtual int corners() const { return 0; }
};
struct Square : Shape {
  int corners() const override { return 4; }
};

__attribute__((noipa)) const Shape& pick(int i) {
  static const Shape shape;
  static const Square square;
  return i > 0 ? static_cast<const Shape&>(square) : shape;
}

int main() { return typeid(pick(1)) == typeid(Square) ? 0 : 1; }
