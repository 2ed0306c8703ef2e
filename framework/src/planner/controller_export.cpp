#include "planner/controller_export.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <limits>
#include <map>
#include <sstream>
#include <stdexcept>

namespace chatterlab::planner {

std::vector<char> gcode_letters(const FeedPlan& plan) {
  static const std::map<std::string, char> known{
      {"lower", 'X'}, {"middle", 'Y'}, {"upper", 'Z'}, {"c_axis", 'C'}, {"x_slide", 'X'}};
  static const char fallback[] = {'X', 'Y', 'Z', 'A', 'B', 'C', 'U', 'V', 'W'};
  std::vector<char> letters;
  bool all_known = true;
  for (const MotorAxis& m : plan.motors) {
    const auto it = known.find(m.name);
    all_known = all_known && it != known.end();
    letters.push_back(it != known.end() ? it->second : ' ');
  }
  std::vector<char> sorted = letters;
  std::sort(sorted.begin(), sorted.end());
  if (!all_known || std::adjacent_find(sorted.begin(), sorted.end()) != sorted.end()) {
    if (plan.motors.size() > std::size(fallback))
      throw std::invalid_argument("G-code has letters for at most 9 axes");
    for (std::size_t m = 0; m < plan.motors.size(); ++m) letters[m] = fallback[m];
  }
  return letters;
}

std::string gcode_program(const FeedPlan& plan, const std::vector<std::string>& comments) {
  const std::vector<char> letters = gcode_letters(plan);
  std::string out;
  for (const std::string& c : comments) out += fmt::format("; {}\n", c);
  for (std::size_t m = 0; m < plan.motors.size(); ++m)
    out += fmt::format("; {} = {} motor ({}), {} per step\n", letters[m], plan.motors[m].name,
                       plan.motors[m].position_name.empty() ? plan.motors[m].name : plan.motors[m].position_name,
                       plan.motors[m].mm_per_pulse);
  out += "G21 G90\n";
  if (plan.spindle_speed_rpm > 0) out += fmt::format("S{:.6f} M3\n", plan.spindle_speed_rpm);  // work spindle
  std::vector<std::int64_t> steps(plan.motors.size(), 0);
  auto axes = [&] {
    std::string words;
    for (std::size_t m = 0; m < plan.motors.size(); ++m)
      words += fmt::format(" {}{:.9f}", letters[m],
                           plan.initial_position_mm[m] + static_cast<double>(steps[m]) * plan.motors[m].mm_per_pulse);
    return words;
  };
  out += "G0" + axes() + "\n";
  out += "G93\n";
  for (const PlanSegment& seg : plan.segments) {
    for (std::size_t m = 0; m < plan.motors.size(); ++m) steps[m] += seg.pulses[m];
    out += fmt::format("G1{} F{:.12g}\n", axes(), 60.0 / seg.duration_s);
  }
  out += plan.spindle_speed_rpm > 0 ? "G94\nM5\nM2\n" : "G94\nM2\n";
  return out;
}

namespace {

// The words of a G-code line without its comment: letter -> number.
std::map<char, double> words_of(const std::string& line, std::size_t line_number) {
  std::string code = line.substr(0, line.find(';'));
  std::map<char, double> words;
  std::size_t i = 0;
  while (i < code.size()) {
    if (std::isspace(static_cast<unsigned char>(code[i]))) {
      ++i;
      continue;
    }
    const char letter = static_cast<char>(std::toupper(static_cast<unsigned char>(code[i])));
    if (!std::isalpha(static_cast<unsigned char>(letter)))
      throw std::invalid_argument(fmt::format("line {}: '{}' is not a G-code word", line_number, code.substr(i)));
    const char* begin = code.c_str() + i + 1;
    char* end = nullptr;
    const double value = std::strtod(begin, &end);
    if (end == begin)
      throw std::invalid_argument(fmt::format("line {}: word {} has no number", line_number, letter));
    // Programs written here carry one G word per line (G21 G90 is read as its last word, G90).
    if (letter != 'G' && letter != 'M' && words.count(letter))
      throw std::invalid_argument(fmt::format("line {}: word {} given twice", line_number, letter));
    words[letter] = value;
    i = static_cast<std::size_t>(end - code.c_str());
  }
  return words;
}

}  // namespace

FeedPlan read_gcode_program(const std::string& text, const FeedPlan& like) {
  const std::vector<char> letters = gcode_letters(like);
  FeedPlan out;
  out.motors = like.motors;
  out.spindle_speed_rpm = like.spindle_speed_rpm;
  std::istringstream in(text);
  std::string line;
  std::size_t number = 0;
  bool inverse_time = false, started = false;
  double t = 0.0;
  std::vector<std::int64_t> previous(like.motors.size(), 0);
  auto positions = [&](const std::map<char, double>& w, std::size_t at) {
    std::vector<double> p(like.motors.size());
    for (std::size_t m = 0; m < like.motors.size(); ++m) {
      const auto it = w.find(letters[m]);
      if (it == w.end())
        throw std::invalid_argument(fmt::format("line {}: no {} word (every move gives every axis)", at, letters[m]));
      p[m] = it->second;
    }
    return p;
  };
  while (std::getline(in, line)) {
    ++number;
    const auto w = words_of(line, number);
    if (w.empty()) continue;
    const auto g = w.find('G');
    if (g == w.end()) continue;  // S/M words
    const int code = static_cast<int>(std::lround(g->second));
    if (code == 93) inverse_time = true;
    else if (code == 94) inverse_time = false;
    else if (code == 0) {
      out.initial_position_mm = positions(w, number);
      started = true;
    } else if (code == 1) {
      if (!started || !inverse_time)
        throw std::invalid_argument(fmt::format("line {}: G1 before the G0 start or outside G93", number));
      const auto f = w.find('F');
      if (f == w.end() || !(f->second > 0))
        throw std::invalid_argument(fmt::format("line {}: G1 needs F > 0 (inverse time, 1/min)", number));
      const std::vector<double> p = positions(w, number);
      PlanSegment seg;
      seg.start_s = t;
      seg.duration_s = 60.0 / f->second;
      for (std::size_t m = 0; m < like.motors.size(); ++m) {
        const std::int64_t s =
            std::llround((p[m] - out.initial_position_mm[m]) / like.motors[m].mm_per_pulse);
        seg.pulses.push_back(s - previous[m]);
        previous[m] = s;
      }
      t += seg.duration_s;
      out.segments.push_back(std::move(seg));
    } else if (code != 21 && code != 90) {
      throw std::invalid_argument(fmt::format("line {}: G{} is not part of a chatterlab program", number, code));
    }
  }
  if (!started) throw std::invalid_argument("no G0 start position");
  return out;
}

std::vector<StepEvent> step_events(const FeedPlan& plan, double tick_hz) {
  std::vector<StepEvent> events;
  for (const PlanSegment& seg : plan.segments)
    for (std::size_t m = 0; m < plan.motors.size(); ++m) {
      const std::int64_t n = std::llabs(seg.pulses[m]);
      for (std::int64_t j = 1; j <= n; ++j) {
        const double time = seg.start_s + (static_cast<double>(j) - 0.5) / static_cast<double>(n) * seg.duration_s;
        events.push_back({std::llround(time * tick_hz), m, seg.pulses[m] > 0 ? 1 : -1});
      }
    }
  std::stable_sort(events.begin(), events.end(), [](const StepEvent& a, const StepEvent& b) {
    return a.tick != b.tick ? a.tick < b.tick : a.motor < b.motor;
  });
  return events;
}

std::string step_table_csv(const FeedPlan& plan, double tick_hz) {
  const std::vector<StepEvent> events = step_events(plan, tick_hz);
  std::string out = "tick,motor,direction\n";
  out.reserve(out.size() + events.size() * 20);
  for (const StepEvent& e : events)
    out += fmt::format("{},{},{}\n", e.tick, plan.motors[e.motor].name, e.direction);
  return out;
}

std::vector<StepEvent> read_step_table(const std::string& text, const FeedPlan& like) {
  std::istringstream in(text);
  std::string line;
  std::getline(in, line);
  if (line != "tick,motor,direction")
    throw std::invalid_argument(fmt::format("line 1: header '{}', expected 'tick,motor,direction'", line));
  std::map<std::string, std::size_t> motor;
  for (std::size_t m = 0; m < like.motors.size(); ++m) motor[like.motors[m].name] = m;
  std::vector<StepEvent> events;
  std::size_t number = 1;
  while (std::getline(in, line)) {
    ++number;
    if (line.empty()) continue;
    const auto c1 = line.find(','), c2 = line.find(',', c1 == std::string::npos ? c1 : c1 + 1);
    if (c1 == std::string::npos || c2 == std::string::npos)
      throw std::invalid_argument(fmt::format("line {}: '{}': expected tick,motor,direction", number, line));
    StepEvent e;
    std::size_t used = 0;
    try {
      e.tick = std::stoll(line.substr(0, c1), &used);
      e.direction = std::stoi(line.substr(c2 + 1));
    } catch (const std::exception&) {
      throw std::invalid_argument(fmt::format("line {}: '{}': tick and direction must be integers", number, line));
    }
    const auto m = motor.find(line.substr(c1 + 1, c2 - c1 - 1));
    if (m == motor.end())
      throw std::invalid_argument(fmt::format("line {}: unknown motor '{}'", number, line.substr(c1 + 1, c2 - c1 - 1)));
    if (e.direction != 1 && e.direction != -1)
      throw std::invalid_argument(fmt::format("line {}: direction {} (must be +1 or -1)", number, e.direction));
    if (!events.empty() && e.tick < events.back().tick)
      throw std::invalid_argument(fmt::format("line {}: tick {} before the previous row's {}", number, e.tick,
                                              events.back().tick));
    e.motor = m->second;
    events.push_back(e);
  }
  return events;
}

ExportCheck check_export(const FeedPlan& plan, const FeedPlan& from_gcode, const std::vector<StepEvent>& events,
                         double tick_hz) {
  ExportCheck c;
  const std::size_t motors = plan.motors.size();
  c.gcode_pulses_identical = from_gcode.segments.size() == plan.segments.size();
  for (std::size_t k = 0; k < plan.segments.size() && c.gcode_pulses_identical; ++k) {
    c.gcode_pulses_identical = from_gcode.segments[k].pulses == plan.segments[k].pulses;
    c.gcode_max_duration_error_s = std::max(
        c.gcode_max_duration_error_s, std::abs(from_gcode.segments[k].duration_s - plan.segments[k].duration_s));
  }
  // Step table: per motor, the i-th event is the plan's i-th pulse of that motor (same
  // direction, time within the tick rounding); positions compared at every segment end.
  std::vector<std::vector<std::pair<double, int>>> pulses(motors);  // exact time, direction
  std::vector<std::size_t> boundary;  // events per motor up to each segment's end
  for (const PlanSegment& seg : plan.segments)
    for (std::size_t m = 0; m < motors; ++m) {
      const std::int64_t n = std::llabs(seg.pulses[m]);
      for (std::int64_t j = 1; j <= n; ++j)
        pulses[m].emplace_back(seg.start_s + (static_cast<double>(j) - 0.5) / static_cast<double>(n) * seg.duration_s,
                               seg.pulses[m] > 0 ? 1 : -1);
    }
  c.step_events = events.size();
  c.step_positions_identical = true;
  std::vector<std::size_t> seen(motors, 0);
  std::vector<std::int64_t> position(motors, 0), planned_position(motors, 0);
  std::vector<double> last_step(motors, -1.0);
  std::vector<int> last_direction(motors, 0);
  c.shortest_step_interval_s = c.shortest_direction_setup_s = std::numeric_limits<double>::infinity();
  std::size_t e = 0;
  for (const PlanSegment& seg : plan.segments) {
    const double end = seg.start_s + seg.duration_s;
    for (std::size_t m = 0; m < motors; ++m) planned_position[m] += seg.pulses[m];
    // Every event up to the segment's end (pulses lie strictly inside their segment).
    for (; e < events.size() && static_cast<double>(events[e].tick) / tick_hz < end; ++e) {
      const StepEvent& ev = events[e];
      const double time = static_cast<double>(ev.tick) / tick_hz;
      if (seen[ev.motor] >= pulses[ev.motor].size() || pulses[ev.motor][seen[ev.motor]].second != ev.direction) {
        c.step_positions_identical = false;
      } else {
        c.step_max_time_error_s = std::max(c.step_max_time_error_s, std::abs(time - pulses[ev.motor][seen[ev.motor]].first));
      }
      ++seen[ev.motor];
      if (last_step[ev.motor] >= 0) {
        const double gap = time - last_step[ev.motor];
        c.shortest_step_interval_s = std::min(c.shortest_step_interval_s, gap);
        if (ev.direction != last_direction[ev.motor])
          c.shortest_direction_setup_s = std::min(c.shortest_direction_setup_s, gap);
      }
      last_step[ev.motor] = time;
      last_direction[ev.motor] = ev.direction;
      position[ev.motor] += ev.direction;
    }
    if (position != planned_position) c.step_positions_identical = false;
  }
  if (e != events.size()) c.step_positions_identical = false;
  return c;
}

ControllerExport export_plan(const FeedPlan& plan, const std::vector<std::string>& comments, double tick_hz) {
  ControllerExport out;
  out.tick_hz = tick_hz;
  out.gcode = gcode_program(plan, comments);
  out.step_table = step_table_csv(plan, tick_hz);
  out.from_gcode = read_gcode_program(out.gcode, plan);
  out.events = read_step_table(out.step_table, plan);
  out.check = check_export(plan, out.from_gcode, out.events, tick_hz);
  return out;
}

}  // namespace chatterlab::planner
