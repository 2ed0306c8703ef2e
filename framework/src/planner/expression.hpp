#pragma once
// The generatrix expression y = f(x) as a syntax tree (the muparser grammar the study files use:
// + - * / ^, unary signs, comparisons, && ||, c ? a : b, the muparser functions, _pi and _e),
// evaluated two ways (docs/planner.md, "Geometry analysis"):
//   - at a point, with exact first and second derivatives (forward-mode differentiation: no
//     finite-difference step, no evaluation outside the range);
//   - over an interval, as enclosures of f, f' and f'' that contain every value the expression
//     takes there, with flags for what could make it non-smooth inside: a switch of abs, sign,
//     rint, min, max, a comparison or a ternary condition (a possible jump or kink), or a
//     function argument that may leave its domain.
// The tree is immutable after parsing, so evaluation is thread-safe (unlike a muparser object).
#include <cstdint>
#include <string>
#include <vector>

#include "planner/interval.hpp"

namespace chatterlab::planner {

struct Jet {
  double v = 0.0, d1 = 0.0, d2 = 0.0;  // f, f', f''
};

struct IntervalJet {
  Interval v, d1, d2;
  bool may_switch = false;   // a non-smooth switch (abs, sign, rint, min/max, ?:, comparison) inside
  bool may_be_undefined = false;  // an argument may leave its function's domain (or divide by 0)
};

class Expression {
 public:
  // Parses `text` with the variable `x`. Throws std::invalid_argument naming the position and
  // what was expected, or an unknown name.
  static Expression parse(const std::string& text);

  double value(double x) const;
  Jet jet(double x) const;
  IntervalJet enclose(const Interval& x) const;
  const std::string& text() const { return text_; }

 private:
  enum class Op : std::uint8_t {
    constant, variable, negate, add, subtract, multiply, divide, power,
    less, greater, less_equal, greater_equal, equal, not_equal, logical_and, logical_or,
    ternary, function, atan2, minimum, maximum, sum, average
  };
  enum class Fn : std::uint8_t {
    sin, cos, tan, asin, acos, atan, sinh, cosh, tanh, asinh, acosh, atanh,
    log2, log10, ln, exp, sqrt, sign, rint, abs
  };
  struct Node {
    Op op = Op::constant;
    Fn fn = Fn::sin;
    double value = 0.0;
    std::vector<int> args;
  };
  friend class ExpressionParser;

  Jet jet_at(int node, double x) const;
  IntervalJet enclose_at(int node, const Interval& x) const;

  std::string text_;
  std::vector<Node> nodes_;
  int root_ = -1;
};

}  // namespace chatterlab::planner
