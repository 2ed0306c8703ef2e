#include "planner/expression.hpp"

#include <fmt/format.h>

#include <cctype>
#include <cmath>
#include <cstdlib>
#include <map>
#include <numbers>
#include <stdexcept>

namespace chatterlab::planner {

// ------------------------------------------------------------------ parsing
// Precedence as muparser 2.3 (lowest first): ?: (right), ||, &&, comparisons, + -, * / and the
// unary signs, ^ (right; its exponent may carry a sign: 2^-1). So -x^2 = -(x^2), 2^3^2 = 512.
class ExpressionParser {
 public:
  ExpressionParser(const std::string& text, Expression& out) : s_(text), out_(out) {}

  int parse() {
    const int root = ternary();
    skip();
    if (pos_ != s_.size()) fail(fmt::format("unexpected \"{}\"", s_.substr(pos_, 8)));
    return root;
  }

 private:
  using Op = Expression::Op;
  using Fn = Expression::Fn;

  [[noreturn]] void fail(const std::string& what) const {
    throw std::invalid_argument(fmt::format("at position {}: {}", pos_ + 1, what));
  }
  void skip() {
    while (pos_ < s_.size() && std::isspace(static_cast<unsigned char>(s_[pos_]))) ++pos_;
  }
  bool accept(const char* token) {
    skip();
    const std::string t(token);
    if (s_.compare(pos_, t.size(), t) != 0) return false;
    // "<" must not take the first character of "<=", nor "=" of "==".
    if ((t == "<" || t == ">") && pos_ + 1 < s_.size() && s_[pos_ + 1] == '=') return false;
    pos_ += t.size();
    return true;
  }
  void expect(const char* token) {
    if (!accept(token)) fail(fmt::format("expected \"{}\"", token));
  }
  int node(Op op, std::vector<int> args, double value = 0.0, Fn fn = Fn::sin) {
    Expression::Node n;
    n.op = op;
    n.fn = fn;
    n.value = value;
    n.args = std::move(args);
    out_.nodes_.push_back(std::move(n));
    return static_cast<int>(out_.nodes_.size()) - 1;
  }

  int ternary() {
    const int condition = logical_or();
    if (!accept("?")) return condition;
    const int yes = ternary();
    expect(":");
    const int no = ternary();
    return node(Op::ternary, {condition, yes, no});
  }
  int logical_or() {
    int left = logical_and();
    while (accept("||")) left = node(Op::logical_or, {left, logical_and()});
    return left;
  }
  int logical_and() {
    int left = comparison();
    while (accept("&&")) left = node(Op::logical_and, {left, comparison()});
    return left;
  }
  int comparison() {
    int left = additive();
    for (;;) {
      Op op;
      if (accept("<=")) op = Op::less_equal;
      else if (accept(">=")) op = Op::greater_equal;
      else if (accept("==")) op = Op::equal;
      else if (accept("!=")) op = Op::not_equal;
      else if (accept("<")) op = Op::less;
      else if (accept(">")) op = Op::greater;
      else return left;
      left = node(op, {left, additive()});
    }
  }
  int additive() {
    int left = multiplicative();
    for (;;) {
      if (accept("+")) left = node(Op::add, {left, multiplicative()});
      else if (accept("-")) left = node(Op::subtract, {left, multiplicative()});
      else return left;
    }
  }
  int multiplicative() {
    int left = signed_factor();
    for (;;) {
      if (accept("*")) left = node(Op::multiply, {left, signed_factor()});
      else if (accept("/")) left = node(Op::divide, {left, signed_factor()});
      else return left;
    }
  }
  // One sign at most, as muparser ("--2" is refused there).
  int signed_factor() {
    if (accept("-")) return node(Op::negate, {power()});
    accept("+");
    return power();
  }
  int power() {
    const int base = primary();
    if (!accept("^")) return base;
    return node(Op::power, {base, signed_power()});
  }
  int signed_power() {  // the exponent: right-associative, may carry one sign
    if (accept("-")) return node(Op::negate, {power()});
    accept("+");
    return power();
  }
  int primary() {
    skip();
    if (pos_ >= s_.size()) fail("unexpected end of the expression");
    const char c = s_[pos_];
    if (std::isdigit(static_cast<unsigned char>(c)) || c == '.') return number();
    if (accept("(")) {
      const int inner = ternary();
      expect(")");
      return inner;
    }
    if (std::isalpha(static_cast<unsigned char>(c)) || c == '_') return name();
    fail(fmt::format("unexpected \"{}\"", c));
  }
  int number() {
    const char* begin = s_.c_str() + pos_;
    char* end = nullptr;
    const double v = std::strtod(begin, &end);
    if (end == begin) fail("expected a number");
    pos_ += static_cast<std::size_t>(end - begin);
    return node(Op::constant, {}, v);
  }
  int name() {
    const std::size_t start = pos_;
    while (pos_ < s_.size() &&
           (std::isalnum(static_cast<unsigned char>(s_[pos_])) || s_[pos_] == '_'))
      ++pos_;
    const std::string id = s_.substr(start, pos_ - start);
    if (id == "x") return node(Op::variable, {});
    if (id == "_pi") return node(Op::constant, {}, std::numbers::pi);
    if (id == "_e") return node(Op::constant, {}, std::numbers::e);
    static const std::map<std::string, Fn> unary{
        {"sin", Fn::sin},     {"cos", Fn::cos},       {"tan", Fn::tan},     {"asin", Fn::asin},
        {"acos", Fn::acos},   {"atan", Fn::atan},     {"sinh", Fn::sinh},   {"cosh", Fn::cosh},
        {"tanh", Fn::tanh},   {"asinh", Fn::asinh},   {"acosh", Fn::acosh}, {"atanh", Fn::atanh},
        {"log2", Fn::log2},   {"log10", Fn::log10},   {"log", Fn::ln},      {"ln", Fn::ln},
        {"exp", Fn::exp},     {"sqrt", Fn::sqrt},     {"sign", Fn::sign},   {"rint", Fn::rint},
        {"abs", Fn::abs}};
    static const std::map<std::string, Op> variadic{
        {"min", Op::minimum}, {"max", Op::maximum}, {"sum", Op::sum}, {"avg", Op::average},
        {"atan2", Op::atan2}};
    const auto u = unary.find(id);
    const auto v = variadic.find(id);
    if (u == unary.end() && v == variadic.end())
      fail(fmt::format("unknown name \"{}\" (the variable is x; constants _pi, _e)", id));
    expect("(");
    std::vector<int> args{ternary()};
    while (accept(",")) args.push_back(ternary());
    expect(")");
    if (u != unary.end()) {
      if (args.size() != 1) fail(fmt::format("{} takes one argument", id));
      return node(Op::function, args, 0.0, u->second);
    }
    if (v->second == Op::atan2 && args.size() != 2) fail("atan2 takes two arguments");
    return node(v->second, args);
  }

  const std::string& s_;
  Expression& out_;
  std::size_t pos_ = 0;
};

Expression Expression::parse(const std::string& text) {
  Expression e;
  e.text_ = text;
  e.root_ = ExpressionParser(text, e).parse();
  return e;
}

// ------------------------------------------------------------------ point jets
namespace {

// phi(u) with phi' and phi'' at u, chained: (phi o u)' = phi' u', (phi o u)'' = phi'' u'^2 + phi' u''.
Jet chain(const Jet& u, double value, double p1, double p2) {
  // An exactly constant argument keeps zero derivatives even where phi' is infinite.
  const double d1 = u.d1 == 0.0 ? 0.0 : p1 * u.d1;
  const double d2 = (u.d1 == 0.0 ? 0.0 : p2 * u.d1 * u.d1) + (u.d2 == 0.0 ? 0.0 : p1 * u.d2);
  return {value, d1, d2};
}

Jet power_jet(const Jet& a, const Jet& b) {
  if (b.d1 == 0.0 && b.d2 == 0.0) {  // constant exponent c: the power rule (a < 0 allowed)
    const double c = b.v;
    const double p1 = c == 0.0 ? 0.0 : c * std::pow(a.v, c - 1);
    const double p2 = (c == 0.0 || c == 1.0) ? 0.0 : c * (c - 1) * std::pow(a.v, c - 2);
    return chain(a, std::pow(a.v, c), p1, p2);
  }
  // a^b = exp(b ln a), a > 0.
  const double l = std::log(a.v), l1 = a.d1 / a.v, l2 = (a.d2 * a.v - a.d1 * a.d1) / (a.v * a.v);
  const Jet g{b.v * l, b.d1 * l + b.v * l1, b.d2 * l + 2 * b.d1 * l1 + b.v * l2};
  const double e = std::pow(a.v, b.v);
  return {e, e * g.d1, e * (g.d2 + g.d1 * g.d1)};
}

Jet constant_jet(double v) { return {v, 0.0, 0.0}; }

}  // namespace

double Expression::value(double x) const { return jet_at(root_, x).v; }
Jet Expression::jet(double x) const { return jet_at(root_, x); }

Jet Expression::jet_at(int index, double x) const {
  const Node& n = nodes_[static_cast<std::size_t>(index)];
  auto arg = [&](std::size_t i) { return jet_at(n.args[i], x); };
  switch (n.op) {
    case Op::constant: return constant_jet(n.value);
    case Op::variable: return {x, 1.0, 0.0};
    case Op::negate: {
      const Jet a = arg(0);
      return {-a.v, -a.d1, -a.d2};
    }
    case Op::add: {
      const Jet a = arg(0), b = arg(1);
      return {a.v + b.v, a.d1 + b.d1, a.d2 + b.d2};
    }
    case Op::subtract: {
      const Jet a = arg(0), b = arg(1);
      return {a.v - b.v, a.d1 - b.d1, a.d2 - b.d2};
    }
    case Op::multiply: {
      const Jet a = arg(0), b = arg(1);
      return {a.v * b.v, a.d1 * b.v + a.v * b.d1, a.d2 * b.v + 2 * a.d1 * b.d1 + a.v * b.d2};
    }
    case Op::divide: {
      const Jet a = arg(0), b = arg(1);
      const double q = a.v / b.v, q1 = (a.d1 - q * b.d1) / b.v;
      return {q, q1, (a.d2 - 2 * q1 * b.d1 - q * b.d2) / b.v};
    }
    case Op::power: return power_jet(arg(0), arg(1));
    case Op::less: return constant_jet(arg(0).v < arg(1).v ? 1.0 : 0.0);
    case Op::greater: return constant_jet(arg(0).v > arg(1).v ? 1.0 : 0.0);
    case Op::less_equal: return constant_jet(arg(0).v <= arg(1).v ? 1.0 : 0.0);
    case Op::greater_equal: return constant_jet(arg(0).v >= arg(1).v ? 1.0 : 0.0);
    case Op::equal: return constant_jet(arg(0).v == arg(1).v ? 1.0 : 0.0);
    case Op::not_equal: return constant_jet(arg(0).v != arg(1).v ? 1.0 : 0.0);
    case Op::logical_and: return constant_jet(arg(0).v != 0.0 && arg(1).v != 0.0 ? 1.0 : 0.0);
    case Op::logical_or: return constant_jet(arg(0).v != 0.0 || arg(1).v != 0.0 ? 1.0 : 0.0);
    case Op::ternary: return arg(0).v != 0.0 ? arg(1) : arg(2);
    case Op::atan2: {
      const Jet y = arg(0), xx = arg(1);
      const double r2 = y.v * y.v + xx.v * xx.v;
      // d atan2 = (x dy - y dx) / r^2
      const double n1 = xx.v * y.d1 - y.v * xx.d1;
      const double d1 = n1 / r2;
      const double n2 = xx.v * y.d2 - y.v * xx.d2;  // derivative of n1: x' y' - y' x' cancel
      const double r2d = 2 * (y.v * y.d1 + xx.v * xx.d1);
      return {std::atan2(y.v, xx.v), d1, (n2 - d1 * r2d) / r2};
    }
    case Op::minimum:
    case Op::maximum: {
      Jet best = arg(0);
      for (std::size_t i = 1; i < n.args.size(); ++i) {
        const Jet c = arg(i);
        if (n.op == Op::minimum ? c.v < best.v : c.v > best.v) best = c;
      }
      return best;
    }
    case Op::sum:
    case Op::average: {
      Jet s{};
      for (std::size_t i = 0; i < n.args.size(); ++i) {
        const Jet c = arg(i);
        s = {s.v + c.v, s.d1 + c.d1, s.d2 + c.d2};
      }
      if (n.op == Op::average) {
        const auto k = static_cast<double>(n.args.size());
        s = {s.v / k, s.d1 / k, s.d2 / k};
      }
      return s;
    }
    case Op::function: break;
  }
  const Jet u = arg(0);
  const double v = u.v;
  switch (n.fn) {
    case Fn::sin: return chain(u, std::sin(v), std::cos(v), -std::sin(v));
    case Fn::cos: return chain(u, std::cos(v), -std::sin(v), -std::cos(v));
    case Fn::tan: {
      const double t = std::tan(v);
      return chain(u, t, 1 + t * t, 2 * t * (1 + t * t));
    }
    case Fn::asin: return chain(u, std::asin(v), 1 / std::sqrt(1 - v * v), v / std::pow(1 - v * v, 1.5));
    case Fn::acos: return chain(u, std::acos(v), -1 / std::sqrt(1 - v * v), -v / std::pow(1 - v * v, 1.5));
    case Fn::atan: return chain(u, std::atan(v), 1 / (1 + v * v), -2 * v / ((1 + v * v) * (1 + v * v)));
    case Fn::sinh: return chain(u, std::sinh(v), std::cosh(v), std::sinh(v));
    case Fn::cosh: return chain(u, std::cosh(v), std::sinh(v), std::cosh(v));
    case Fn::tanh: {
      const double t = std::tanh(v);
      return chain(u, t, 1 - t * t, -2 * t * (1 - t * t));
    }
    case Fn::asinh: return chain(u, std::asinh(v), 1 / std::sqrt(1 + v * v), -v / std::pow(1 + v * v, 1.5));
    case Fn::acosh: return chain(u, std::acosh(v), 1 / std::sqrt(v * v - 1), -v / std::pow(v * v - 1, 1.5));
    case Fn::atanh: return chain(u, std::atanh(v), 1 / (1 - v * v), 2 * v / ((1 - v * v) * (1 - v * v)));
    case Fn::log2: return chain(u, std::log2(v), 1 / (v * std::numbers::ln2), -1 / (v * v * std::numbers::ln2));
    case Fn::log10: return chain(u, std::log10(v), 1 / (v * std::numbers::ln10), -1 / (v * v * std::numbers::ln10));
    case Fn::ln: return chain(u, std::log(v), 1 / v, -1 / (v * v));
    case Fn::exp: {
      const double e = std::exp(v);
      return chain(u, e, e, e);
    }
    case Fn::sqrt: {
      const double r = std::sqrt(v);
      return chain(u, r, 0.5 / r, -0.25 / (r * v));
    }
    case Fn::sign: return constant_jet(v > 0 ? 1.0 : v < 0 ? -1.0 : 0.0);
    case Fn::rint: return constant_jet(std::floor(v + 0.5));  // muparser's rint
    case Fn::abs: return chain(u, std::abs(v), v > 0 ? 1.0 : v < 0 ? -1.0 : 0.0, 0.0);
  }
  return {};
}

// ------------------------------------------------------------------ interval jets
namespace {

IntervalJet chain(const IntervalJet& u, const Interval& value, const Interval& p1, const Interval& p2) {
  IntervalJet out;
  out.v = value;
  out.d1 = p1 * u.d1;
  out.d2 = p2 * sqr(u.d1) + p1 * u.d2;
  out.may_switch = u.may_switch;
  out.may_be_undefined = u.may_be_undefined || !value.finite();
  return out;
}

IntervalJet constant_interval(double v) {
  IntervalJet j;
  j.v = Interval::point(v);
  return j;
}

IntervalJet merge_flags(IntervalJet out, std::initializer_list<const IntervalJet*> from) {
  for (const IntervalJet* f : from) {
    out.may_switch = out.may_switch || f->may_switch;
    out.may_be_undefined = out.may_be_undefined || f->may_be_undefined;
  }
  return out;
}

// A 0/1 value that may switch inside when both outcomes are possible.
IntervalJet truth(bool can_be_true, bool can_be_false, const IntervalJet& a, const IntervalJet& b) {
  IntervalJet out;
  out.v = {can_be_false ? 0.0 : 1.0, can_be_true ? 1.0 : 0.0};
  out = merge_flags(out, {&a, &b});
  out.may_switch = out.may_switch || (can_be_true && can_be_false);
  return out;
}

// x^c for a constant real exponent over an interval (x >= 0 unless c is whole).
Interval power_interval(const Interval& x, double c, bool& undefined) {
  if (c == std::round(c) && std::abs(c) < 1e9) {
    const int n = static_cast<int>(c);
    if (n < 0 && x.contains(0.0)) undefined = true;
    return pow_int(x, n);
  }
  if (x.lo < 0) undefined = true;
  const Interval nonneg{std::max(x.lo, 0.0), std::max(x.hi, 0.0)};
  if (c < 0 && nonneg.lo == 0.0) undefined = true;
  const double l = std::pow(nonneg.lo, c), h = std::pow(nonneg.hi, c);
  return interval_detail::widen(std::min(l, h), std::max(l, h), 2);
}

const Interval one = Interval::point(1.0);

}  // namespace

IntervalJet Expression::enclose(const Interval& x) const { return enclose_at(root_, x); }

IntervalJet Expression::enclose_at(int index, const Interval& x) const {
  const Node& n = nodes_[static_cast<std::size_t>(index)];
  auto arg = [&](std::size_t i) { return enclose_at(n.args[i], x); };
  switch (n.op) {
    case Op::constant: return constant_interval(n.value);
    case Op::variable: {
      IntervalJet j;
      j.v = x;
      j.d1 = one;
      j.d2 = Interval::point(0.0);
      return j;
    }
    case Op::negate: {
      IntervalJet a = arg(0);
      a.v = -a.v;
      a.d1 = -a.d1;
      a.d2 = -a.d2;
      return a;
    }
    case Op::add:
    case Op::subtract: {
      const IntervalJet a = arg(0), b = arg(1);
      IntervalJet out;
      const bool plus = n.op == Op::add;
      out.v = plus ? a.v + b.v : a.v - b.v;
      out.d1 = plus ? a.d1 + b.d1 : a.d1 - b.d1;
      out.d2 = plus ? a.d2 + b.d2 : a.d2 - b.d2;
      return merge_flags(out, {&a, &b});
    }
    case Op::multiply: {
      const IntervalJet a = arg(0), b = arg(1);
      IntervalJet out;
      out.v = a.v * b.v;
      out.d1 = a.d1 * b.v + a.v * b.d1;
      out.d2 = a.d2 * b.v + Interval::point(2.0) * a.d1 * b.d1 + a.v * b.d2;
      return merge_flags(out, {&a, &b});
    }
    case Op::divide: {
      const IntervalJet a = arg(0), b = arg(1);
      IntervalJet out;
      const Interval inv = one / b.v;
      out.v = a.v * inv;
      out.d1 = (a.d1 - out.v * b.d1) * inv;
      out.d2 = (a.d2 - Interval::point(2.0) * out.d1 * b.d1 - out.v * b.d2) * inv;
      out = merge_flags(out, {&a, &b});
      out.may_be_undefined = out.may_be_undefined || b.v.contains(0.0);
      return out;
    }
    case Op::power: {
      const IntervalJet a = arg(0), b = arg(1);
      const bool constant_exponent = b.v.lo == b.v.hi && b.d1.lo == 0.0 && b.d1.hi == 0.0 &&
                                     b.d2.lo == 0.0 && b.d2.hi == 0.0;
      bool undefined = false;
      IntervalJet out;
      if (constant_exponent) {
        const double c = b.v.lo;
        const Interval p1 = c == 0.0 ? Interval::point(0.0)
                                     : Interval::point(c) * power_interval(a.v, c - 1, undefined);
        bool ignored = false;  // f'' may blow up where f is still fine (x^1.5 at 0): flagged below
        const Interval p2 = (c == 0.0 || c == 1.0)
                                ? Interval::point(0.0)
                                : Interval::point(c * (c - 1)) * power_interval(a.v, c - 2, ignored);
        out = chain(a, power_interval(a.v, c, undefined), p1, p2);
      } else {
        if (!(a.v.lo > 0)) undefined = true;
        const Interval l = log(a.v);
        const Interval e = exp(b.v * l);
        const Interval l1 = a.d1 / a.v, l2 = (a.d2 * a.v - sqr(a.d1)) / sqr(a.v);
        const Interval g1 = b.d1 * l + b.v * l1;
        const Interval g2 = b.d2 * l + Interval::point(2.0) * b.d1 * l1 + b.v * l2;
        out.v = e;
        out.d1 = e * g1;
        out.d2 = e * (g2 + sqr(g1));
      }
      out = merge_flags(out, {&a, &b});
      out.may_be_undefined = out.may_be_undefined || undefined;
      return out;
    }
    case Op::less:
    case Op::greater:
    case Op::less_equal:
    case Op::greater_equal:
    case Op::equal:
    case Op::not_equal: {
      const IntervalJet a = arg(0), b = arg(1);
      const Interval d = a.v - b.v;  // the comparison of d with 0
      bool can_true = false, can_false = false;
      switch (n.op) {
        case Op::less: can_true = d.lo < 0; can_false = d.hi >= 0; break;
        case Op::greater: can_true = d.hi > 0; can_false = d.lo <= 0; break;
        case Op::less_equal: can_true = d.lo <= 0; can_false = d.hi > 0; break;
        case Op::greater_equal: can_true = d.hi >= 0; can_false = d.lo < 0; break;
        case Op::equal: can_true = d.contains(0.0); can_false = !(d.lo == 0 && d.hi == 0); break;
        default: can_true = !(d.lo == 0 && d.hi == 0); can_false = d.contains(0.0); break;
      }
      return truth(can_true, can_false, a, b);
    }
    case Op::logical_and:
    case Op::logical_or: {
      const IntervalJet a = arg(0), b = arg(1);
      auto can_be_true = [](const IntervalJet& j) { return !(j.v.lo == 0 && j.v.hi == 0); };
      auto can_be_false = [](const IntervalJet& j) { return j.v.contains(0.0); };
      if (n.op == Op::logical_and)
        return truth(can_be_true(a) && can_be_true(b), can_be_false(a) || can_be_false(b), a, b);
      return truth(can_be_true(a) || can_be_true(b), can_be_false(a) && can_be_false(b), a, b);
    }
    case Op::ternary: {
      const IntervalJet c = arg(0);
      const bool can_true = !(c.v.lo == 0 && c.v.hi == 0), can_false = c.v.contains(0.0);
      if (can_true && !can_false) return merge_flags(arg(1), {&c});
      if (can_false && !can_true) return merge_flags(arg(2), {&c});
      const IntervalJet a = arg(1), b = arg(2);
      IntervalJet out;
      out.v = hull(a.v, b.v);
      out.d1 = hull(a.d1, b.d1);
      out.d2 = hull(a.d2, b.d2);
      out = merge_flags(out, {&c, &a, &b});
      out.may_switch = true;
      return out;
    }
    case Op::atan2: {
      const IntervalJet y = arg(0), xx = arg(1);
      IntervalJet out;
      if (xx.v.lo > 0) {  // atan(y/x): no branch cut inside
        const Interval q = y.v / xx.v;
        out.v = atan(q);
      } else {
        out.v = {-std::numbers::pi, std::numbers::pi};
        if (y.v.contains(0.0)) out.may_switch = true;  // the branch cut (a jump of 2 pi)
      }
      const Interval r2 = sqr(y.v) + sqr(xx.v);
      const Interval n1 = xx.v * y.d1 - y.v * xx.d1;
      out.d1 = n1 / r2;
      const Interval r2d = Interval::point(2.0) * (y.v * y.d1 + xx.v * xx.d1);
      out.d2 = (xx.v * y.d2 - y.v * xx.d2 - out.d1 * r2d) / r2;
      out = merge_flags(out, {&y, &xx});
      out.may_be_undefined = out.may_be_undefined || r2.contains(0.0);
      return out;
    }
    case Op::minimum:
    case Op::maximum: {
      std::vector<IntervalJet> a;
      for (std::size_t i = 0; i < n.args.size(); ++i) a.push_back(arg(i));
      // The arguments that can be the extreme somewhere in x: those not beaten everywhere.
      const bool minimum = n.op == Op::minimum;
      double bound = minimum ? a[0].v.hi : a[0].v.lo;
      for (const auto& j : a) bound = minimum ? std::min(bound, j.v.hi) : std::max(bound, j.v.lo);
      IntervalJet out;
      bool first = true;
      std::size_t candidates = 0;
      for (const auto& j : a) {
        if (minimum ? j.v.lo > bound : j.v.hi < bound) {
          out = merge_flags(out, {&j});
          continue;
        }
        ++candidates;
        if (first) {
          const bool s = out.may_switch, u = out.may_be_undefined;
          out = j;
          out.may_switch = out.may_switch || s;
          out.may_be_undefined = out.may_be_undefined || u;
          first = false;
        } else {
          out.v = hull(out.v, j.v);
          out.d1 = hull(out.d1, j.d1);
          out.d2 = hull(out.d2, j.d2);
          out = merge_flags(out, {&j});
        }
      }
      if (candidates > 1) out.may_switch = true;
      if (minimum) out.v.hi = std::min(out.v.hi, bound); else out.v.lo = std::max(out.v.lo, bound);
      return out;
    }
    case Op::sum:
    case Op::average: {
      IntervalJet s = constant_interval(0.0);
      for (std::size_t i = 0; i < n.args.size(); ++i) {
        const IntervalJet c = arg(i);
        s.v = s.v + c.v;
        s.d1 = s.d1 + c.d1;
        s.d2 = s.d2 + c.d2;
        s = merge_flags(s, {&c});
      }
      if (n.op == Op::average) {
        const Interval k = Interval::point(1.0 / static_cast<double>(n.args.size()));
        s.v = s.v * k;
        s.d1 = s.d1 * k;
        s.d2 = s.d2 * k;
      }
      return s;
    }
    case Op::function: break;
  }
  const IntervalJet u = arg(0);
  const Interval& v = u.v;
  IntervalJet out;
  bool undefined = false, switches = false;
  switch (n.fn) {
    case Fn::sin: out = chain(u, sin(v), cos(v), -sin(v)); break;
    case Fn::cos: out = chain(u, cos(v), -sin(v), -cos(v)); break;
    case Fn::tan: {
      // A pole pi/2 + k pi inside: unbounded.
      const double k = std::ceil((v.lo - std::numbers::pi / 2) / std::numbers::pi);
      if (!v.finite() || std::numbers::pi / 2 + k * std::numbers::pi <= v.hi) {
        undefined = true;
        out = chain(u, Interval::entire(), Interval::entire(), Interval::entire());
      } else {
        const Interval t = interval_detail::increasing(v, [](double a) { return std::tan(a); });
        const Interval p1 = one + sqr(t);
        out = chain(u, t, p1, Interval::point(2.0) * t * p1);
      }
      break;
    }
    case Fn::asin:
    case Fn::acos: {
      if (v.lo < -1 || v.hi > 1) undefined = true;
      const Interval c{std::max(v.lo, -1.0), std::min(v.hi, 1.0)};
      const Interval s = one - sqr(c);
      if (s.lo <= 0) undefined = true;
      const Interval p1 = one / sqrt(s), p2 = c / (s * sqrt(s));
      if (n.fn == Fn::asin)
        out = chain(u, interval_detail::increasing(c, [](double a) { return std::asin(a); }), p1, p2);
      else
        out = chain(u, interval_detail::widen(std::acos(c.hi), std::acos(c.lo), 2), -p1, -p2);
      break;
    }
    case Fn::atan: {
      const Interval s = one + sqr(v);
      out = chain(u, atan(v), one / s, Interval::point(-2.0) * v / sqr(s));
      break;
    }
    case Fn::sinh: out = chain(u, sinh(v), cosh(v), sinh(v)); break;
    case Fn::cosh: out = chain(u, cosh(v), sinh(v), cosh(v)); break;
    case Fn::tanh: {
      const Interval t = tanh(v), p1 = one - sqr(t);
      out = chain(u, t, p1, Interval::point(-2.0) * t * p1);
      break;
    }
    case Fn::asinh: {
      const Interval s = one + sqr(v);
      out = chain(u, asinh(v), one / sqrt(s), -v / (s * sqrt(s)));
      break;
    }
    case Fn::acosh: {
      if (v.lo < 1) undefined = true;
      const Interval c{std::max(v.lo, 1.0), std::max(v.hi, 1.0)};
      const Interval s = sqr(c) - one;
      if (s.lo <= 0) undefined = true;
      out = chain(u, interval_detail::increasing(c, [](double a) { return std::acosh(a); }),
                  one / sqrt(s), -c / (s * sqrt(s)));
      break;
    }
    case Fn::atanh: {
      if (v.lo <= -1 || v.hi >= 1) undefined = true;
      const Interval s = one - sqr(v);
      out = chain(u, interval_detail::increasing(v, [](double a) { return std::atanh(a); }), one / s,
                  Interval::point(2.0) * v / sqr(s));
      break;
    }
    case Fn::log2:
    case Fn::log10:
    case Fn::ln: {
      if (v.lo <= 0) undefined = true;
      const double scale = n.fn == Fn::ln ? 1.0 : n.fn == Fn::log2 ? std::numbers::ln2 : std::numbers::ln10;
      const Interval positive{std::max(v.lo, 0.0), std::max(v.hi, 0.0)};
      const Interval l = log(positive) * Interval::point(1.0 / scale);
      const Interval inv = one / positive;
      out = chain(u, l, inv * Interval::point(1.0 / scale), -sqr(inv) * Interval::point(1.0 / scale));
      break;
    }
    case Fn::exp: {
      const Interval e = exp(v);
      out = chain(u, e, e, e);
      break;
    }
    case Fn::sqrt: {
      if (v.lo < 0) undefined = true;
      const Interval r = sqrt(v);
      const Interval p1 = Interval::point(0.5) / r;  // unbounded where v reaches 0
      out = chain(u, r, p1, Interval::point(-0.25) / (r * sqr(r)));
      break;
    }
    // Switches are tested on closed intervals: a kink exactly on an end shows in both neighbours.
    case Fn::sign:
      switches = v.contains(0.0) && v.lo != v.hi;
      out = constant_interval(0.0);
      out.v = {v.lo > 0 ? 1.0 : v.hi < 0 ? -1.0 : (v.lo < 0 ? -1.0 : 0.0),
               v.hi < 0 ? -1.0 : v.lo > 0 ? 1.0 : (v.hi > 0 ? 1.0 : 0.0)};
      out = merge_flags(out, {&u});
      break;
    case Fn::rint: {
      const double l = std::floor(v.lo + 0.5), h = std::floor(v.hi + 0.5);
      switches = l != h;
      out = constant_interval(0.0);
      out.v = {l, h};
      out = merge_flags(out, {&u});
      break;
    }
    case Fn::abs: {
      switches = v.contains(0.0) && v.lo != v.hi;
      const Interval s = v.lo == 0.0 && v.hi == 0.0 ? Interval::point(0.0)
                         : v.contains(0.0)            ? Interval{-1.0, 1.0}
                         : Interval::point(v.lo > 0 ? 1.0 : -1.0);
      out = chain(u, abs(v), s, Interval::point(0.0));
      break;
    }
  }
  out.may_switch = out.may_switch || switches;
  out.may_be_undefined = out.may_be_undefined || undefined;
  return out;
}

}  // namespace chatterlab::planner
