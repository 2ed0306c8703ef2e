// Study kit: the plots of a machine given by a measured FRF (chatterlab/kit/plots.hpp).
#include <fmt/format.h>

#include <algorithm>
#include <cmath>

#include "chatterlab/kit/plots.hpp"
#include "chatterlab/modal_fit.hpp"

namespace chatterlab::kit {

namespace {

// Appends a series with its colour and width (Curves::looks runs parallel to Curves::series).
void add(plot::Curves& c, plot::Series s, std::string colour, double width = 0.0) {
  c.series.push_back(std::move(s));
  c.looks.push_back({std::move(colour), width});
}

std::vector<double> fit_grid(const ModalFit& fit) {
  std::vector<double> f;
  constexpr int n = 2000;
  for (int i = 0; i <= n; ++i)
    f.push_back(fit.min_frequency_hz + (fit.max_frequency_hz - fit.min_frequency_hz) * i / n);
  return f;
}

std::string fit_words(const ModalFit& fit) {
  return fmt::format("{} modes, relative misfit {:.2g} %", fit.modes.size(), 100.0 * fit.relative_misfit);
}

void plot_magnitude(const MeasuredFrf& frf, const ModalFit* fit, const std::string& title,
                    const std::filesystem::path& dir, Figures& figures) {
  plot::Curves c;
  c.title = fit ? fmt::format("{}: measured FRF and fit ({})", title, fit_words(*fit)) : fmt::format("{}: measured FRF", title);
  c.x_label = "frequency [Hz]";
  c.y_label = "receptance |H| [m/N]";
  c.log_y = true;
  plot::Series measured{fmt::format("measured ({}, as receptance)", to_string(frf.measured_as)), frf.frequency_hz, {},
                        fit ? "points" : "lines"};
  for (const Complex& h : frf.receptance_m_per_n) measured.y.push_back(std::abs(h));
  add(c, measured, "#7f7f7f", fit ? 0.0 : 1.5);
  if (fit) {
    plot::Series synthesised{"synthesised from the fit", fit_grid(*fit), {}, "lines"};
    for (double f : synthesised.x) synthesised.y.push_back(std::abs(fit->receptance(f)));
    add(c, synthesised, "#d55e00", 2.0);
  }
  figures.render(c, dir, "frf_fit");
}

void plot_parts(const MeasuredFrf& frf, const ModalFit* fit, const std::string& title, const std::filesystem::path& dir,
                Figures& figures) {
  plot::Curves c;
  c.title = fmt::format("{}: real and imaginary parts of the receptance", title);
  c.x_label = "frequency [Hz]";
  c.y_label = "receptance [m/N]";
  plot::Series re{"measured real part", frf.frequency_hz, {}, fit ? "points" : "lines"};
  plot::Series im{"measured imaginary part", frf.frequency_hz, {}, fit ? "points" : "lines"};
  for (const Complex& h : frf.receptance_m_per_n) {
    re.y.push_back(h.real());
    im.y.push_back(h.imag());
  }
  add(c, re, "#56b4e9");
  add(c, im, "#e69f00");
  if (fit) {
    plot::Series fit_re{"fit real part", fit_grid(*fit), {}, "lines"};
    plot::Series fit_im{"fit imaginary part", fit_grid(*fit), {}, "lines"};
    for (double f : fit_re.x) {
      fit_re.y.push_back(fit->receptance(f).real());
      fit_im.y.push_back(fit->receptance(f).imag());
    }
    add(c, fit_re, "#0072b2");
    add(c, fit_im, "#d55e00");
  }
  c.reference_y = 0.0;
  figures.render(c, dir, "frf_fit_parts");
}

void plot_stabilisation(const MeasuredFrf& frf, const ModalFit& fit, const std::string& title,
                        const std::filesystem::path& dir, Figures& figures) {
  plot::Curves c;
  c.title = fmt::format("{}: stabilisation diagram (LSCF, orders 2-{})", title, fit.orders.back());
  c.x_label = "frequency [Hz]";
  c.y_label = "model order";
  const double top = fit.orders.back() + 2.0;
  // |H| behind the poles, its log scaled onto the order axis.
  plot::Series h{"|H| measured (log, scaled)", {}, {}, "lines"};
  double lo = INFINITY, hi = -INFINITY;
  for (const Complex& v : frf.receptance_m_per_n) lo = std::min(lo, std::log(std::abs(v))), hi = std::max(hi, std::log(std::abs(v)));
  for (std::size_t i = 0; i < frf.frequency_hz.size(); ++i) {
    if (frf.frequency_hz[i] < fit.min_frequency_hz || frf.frequency_hz[i] > fit.max_frequency_hz) continue;
    h.x.push_back(frf.frequency_hz[i]);
    h.y.push_back(hi > lo ? top * (std::log(std::abs(frf.receptance_m_per_n[i])) - lo) / (hi - lo) : 0.0);
  }
  plot::Series fresh{"new pole", {}, {}, "points"};
  plot::Series frequency{"stable in frequency", {}, {}, "points"};
  plot::Series stable{"stable in frequency and damping", {}, {}, "points"};
  for (const StabilisationPole& p : fit.stabilisation) {
    plot::Series& s = p.status == StabilisationPole::Status::stable             ? stable
                      : p.status == StabilisationPole::Status::frequency_stable ? frequency
                                                                                : fresh;
    s.x.push_back(p.frequency_hz);
    s.y.push_back(p.order);
  }
  plot::Series modes{fmt::format("selected modes ({})", fit.modes.size()), {}, {}, "impulses"};
  for (const FittedMode& m : fit.modes) {
    modes.x.push_back(m.frequency_hz);
    modes.y.push_back(top);
  }
  add(c, h, "#cfcfcf", 1.0);
  add(c, modes, "#009e73", 2.0);
  add(c, fresh, "#bdbdbd");
  add(c, frequency, "#e69f00");
  add(c, stable, "#0072b2");
  c.y_range = {{0.0, top}};
  figures.render(c, dir, "stabilisation_diagram");
}

}  // namespace

void plot_measured_machine(const MeasuredMachine& machine, const std::string& title,
                           const std::filesystem::path& out_dir, Figures& figures) {
  const MeasuredFrf& frf = machine.measured_frf();
  const ModalFit* fit = machine.modal_fit();
  plot_magnitude(frf, fit, title, out_dir, figures);
  plot_parts(frf, fit, title, out_dir, figures);
  if (fit) plot_stabilisation(frf, *fit, title, out_dir, figures);
}

}  // namespace chatterlab::kit
