// The projectile's measures of instability (thesis section 3.4) from the series of a run (run.h5,
// run/run_output.hpp), and the dominant period of an oscillation from its spectrum (thesis
// section 5.9, Table 5.3).
// Equations: docs/models.md §11.
#pragma once

#include <string>
#include <utility>
#include <vector>

namespace mesopen {

// The series of one run that the measures need (SI units, per metre of depth).
struct RunSeries {
  std::vector<double> time;                // [s]
  std::vector<double> depth;               // deepest point below its start [m]
  std::vector<double> com_x;               // centre of mass, x [m]
  std::vector<double> vx;                  // centre-of-mass velocity, x [m/s]
  std::vector<double> rotational_momentum; // H about the centre of mass [kg m^2/s per m]
  std::vector<double> lateral_force;       // F_x on the projectile [N/m]
  std::vector<double> tilt;                // axis rotation from the start, CCW positive [rad]
  std::vector<double> vy;                  // centre-of-mass velocity, y (negative: down) [m/s]
  std::vector<double> axial_force;         // F_y on the projectile [N/m]
  // The energy terms of /series/energy by name ([J/m]; balance_error relative), in file order.
  std::vector<std::pair<std::string, std::vector<double>>> energy;
  double length = 0.0;   // the projectile's initial length [m]
  double mass = 0.0;     // [kg/m]; 0 when the file does not say
  double velocity = 0.0; // initial speed [m/s]
};

// Reads /series and /mesh of run.h5: the projectile's length is the root attribute
// projectile_length, or (in files without it) the initial extent of body 0 along y.
// Throws std::runtime_error naming the file and what is missing.
RunSeries readRunSeries(const std::string &path);

// Lateral impulse up to each sample, the trapezoidal rule
//   I_n = 1/2 sum_{i<n} (F_i + F_{i+1}) (t_{i+1} - t_i),
// whose last value is thesis Eq. 3.14 as printed, 1/2 sum_i F_i (t_{i+1} - t_{i-1}) (with
// t_{-1} = t_0, t_{n+1} = t_n): the impulse, and the average lateral force is impulse / duration.
std::vector<double> cumulativeImpulse(const std::vector<double> &time,
                                      const std::vector<double> &force);

// The dominant period of y(x) from its spectrum: y resampled on a uniform grid of x (linear
// interpolation over increasing x only), a least-squares quadratic removed (the slow trend), a
// Hann window, then the power |sum y_k w_k exp(-2 pi i f x_k)|^2 on a fine grid of frequencies
// from 2 cycles per record (a period no longer than half the record) to a quarter of the grid's
// Nyquist frequency. The period is that of the highest local maximum inside this band (the power
// at the band's low edge is mostly the trend's), refined by a parabola through its three grid
// points; 0 when the power has no local maximum. A maximum within one frequency resolution
// (1 / record) of either edge of the band is flagged: the record does not resolve it (a longer
// period than half the record, or a trend the quadratic did not remove, puts it there).
struct Spectrum {
  std::vector<double> frequency, power; // cycles per unit x; arbitrary units
  double period = 0.0;                  // 1 / the peak frequency [unit of x per cycle]; 0: none
  double peak_over_median = 0.0;        // the peak's power over the median power
  double peak_over_largest = 0.0;       // over the band's largest (1: the peak is the largest)
  bool at_band_edge = false;            // the peak lies within 1 / record of the band's edge
  double x_begin = 0.0, x_end = 0.0;    // the record used
};
Spectrum dominantPeriod(const std::vector<double> &x, const std::vector<double> &y,
                        std::size_t grid = 2048);

// Every measure of one run, as curves against the sample and as figures.
struct Instability {
  std::vector<double> scaled_depth;          // depth / length
  std::vector<double> lateral_impulse;       // [N s/m]
  std::vector<double> average_lateral_force; // I(t) / (t - t_0) [N/m]
  std::vector<double> lateral_displacement;  // com_x - com_x(0) [m]
  std::vector<double> radial_momentum;       // M v_x [kg m/s per m] (empty without the mass)
  Spectrum in_depth;                         // H against scaled depth: period in depth per cycle
  Spectrum in_time;                          // H against time: period in seconds
};
Instability instability(const RunSeries &s);

} // namespace mesopen
