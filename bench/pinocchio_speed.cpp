// Per-call times of Pinocchio's RNEA, CRBA and ABA on one URDF robot, to put beside lsdc's
// (`cargo bench --bench pinocchio_peer`, which prints the same line format).
//
// Build and run through bench/speed_vs_pinocchio.sh, which finds the pip-installed Pinocchio.
// By hand:
//   pinocchio_speed ROBOT.urdf [NAME]
// prints one line
//   NAME rnea_ns crba_ns aba_ns nv
// NAME defaults to the file name without its directory and `.urdf`.
//
// Method: the robot is built with a fixed base (the URDF root link is the universe's child
// through no joint). 256 distinct states are drawn with a fixed seed: every position coordinate
// uniform within its joint limits when both are finite and ordered, else in [-pi, pi]
// (a continuous joint draws its angle and stores cos/sin); v, a and tau uniform in [-1, 1].
// Each algorithm is timed over batches that cycle through the states: the number of calls in a
// batch is chosen so that a batch takes about 20 ms, and the best of 7 batches, divided by its
// number of calls, is the per-call time. Every call uses Pinocchio 4's default arguments
// (Convention::LOCAL for crba and aba; crba fills the upper triangle only, as Pinocchio does).
// Gravity is set to 9.80665 m/s^2 along -z, as in lsdc's URDF import.

#include <chrono>
#include <cmath>
#include <cstdio>
#include <iostream>
#include <random>
#include <string>
#include <vector>

#include <pinocchio/algorithm/aba.hpp>
#include <pinocchio/algorithm/crba.hpp>
#include <pinocchio/algorithm/joint-configuration.hpp>
#include <pinocchio/algorithm/rnea.hpp>
#include <pinocchio/multibody.hpp>
#include <pinocchio/parsers/urdf.hpp>

namespace {

using Vector = Eigen::VectorXd;

struct State {
  Vector q, v, a, tau;
};

// Uniform in [lo, hi] when the limits are usable, else in [-pi, pi].
double draw_coordinate(std::mt19937_64 &rng, double lo, double hi) {
  const bool usable = std::isfinite(lo) && std::isfinite(hi) && lo < hi && hi - lo < 1e6;
  std::uniform_real_distribution<double> dist(usable ? lo : -M_PI, usable ? hi : M_PI);
  return dist(rng);
}

Vector random_configuration(const pinocchio::Model &model, std::mt19937_64 &rng) {
  Vector q = pinocchio::neutral(model);
  for (pinocchio::JointIndex j = 1; j < (pinocchio::JointIndex)model.njoints; ++j) {
    const int iq = model.idx_qs[j];
    const int nq = model.nqs[j];
    const int nv = model.nvs[j];
    if (nq == nv) {
      for (int k = 0; k < nq; ++k)
        q[iq + k] = draw_coordinate(rng, model.lowerPositionLimit[iq + k], model.upperPositionLimit[iq + k]);
    } else if (nq == 2 && nv == 1) {
      // Continuous joint (JointModelRUB*): the angle is stored as (cos, sin).
      const double angle = draw_coordinate(rng, -M_PI, M_PI);
      q[iq] = std::cos(angle);
      q[iq + 1] = std::sin(angle);
    }
    // Other joints (a URDF `floating` or `planar` joint) keep their neutral configuration.
  }
  return q;
}

Vector uniform_vector(int n, std::mt19937_64 &rng) {
  std::uniform_real_distribution<double> dist(-1.0, 1.0);
  Vector x(n);
  for (int i = 0; i < n; ++i) x[i] = dist(rng);
  return x;
}

using Clock = std::chrono::steady_clock;

// Best per-call time, in ns, of `call(state)` cycled over the states.
template <typename Call>
double time_per_call(const std::vector<State> &states, Call call) {
  const double batch_target = 0.020;  // seconds
  // Calibrate: grow the number of calls until a batch takes at least the target.
  long calls = (long)states.size();
  for (;;) {
    const auto start = Clock::now();
    for (long i = 0; i < calls; ++i) call(states[i % states.size()]);
    const double elapsed = std::chrono::duration<double>(Clock::now() - start).count();
    if (elapsed >= batch_target) {
      calls = std::max(calls, (long)std::ceil(calls * batch_target / elapsed));
      break;
    }
    const double factor = elapsed > 0.0 ? std::min(10.0, std::max(2.0, 1.2 * batch_target / elapsed)) : 10.0;
    calls = (long)std::ceil((double)calls * factor);
  }
  double best = INFINITY;
  for (int batch = 0; batch < 7; ++batch) {
    const auto start = Clock::now();
    for (long i = 0; i < calls; ++i) call(states[i % states.size()]);
    const double elapsed = std::chrono::duration<double>(Clock::now() - start).count();
    best = std::min(best, elapsed);
  }
  return best / (double)calls * 1e9;
}

std::string stem(const std::string &path) {
  std::string name = path.substr(path.find_last_of('/') == std::string::npos ? 0 : path.find_last_of('/') + 1);
  const std::string suffix = ".urdf";
  if (name.size() > suffix.size() && name.compare(name.size() - suffix.size(), suffix.size(), suffix) == 0)
    name.resize(name.size() - suffix.size());
  return name;
}

}  // namespace

int main(int argc, char **argv) {
  if (argc < 2 || argc > 3) {
    std::cerr << "usage: " << argv[0] << " ROBOT.urdf [NAME]\n";
    return 2;
  }
  const std::string path = argv[1];
  const std::string name = argc == 3 ? std::string(argv[2]) : stem(path);

  pinocchio::Model model;
  try {
    pinocchio::urdf::buildModel(path, model);
  } catch (const std::exception &e) {
    std::cerr << "error: Pinocchio cannot read `" << path << "`: " << e.what() << "\n";
    return 1;
  }
  model.gravity.linear(Eigen::Vector3d(0.0, 0.0, -9.80665));
  pinocchio::Data data(model);

  std::mt19937_64 rng(20240611);
  std::vector<State> states(256);
  for (State &s : states) {
    s.q = random_configuration(model, rng);
    s.v = uniform_vector(model.nv, rng);
    s.a = uniform_vector(model.nv, rng);
    s.tau = uniform_vector(model.nv, rng);
  }

  // Each call's result feeds a checksum so that no call can be optimised away.
  double checksum = 0.0;
  const double rnea_ns = time_per_call(states, [&](const State &s) {
    checksum += pinocchio::rnea(model, data, s.q, s.v, s.a)[0];
  });
  const double crba_ns = time_per_call(states, [&](const State &s) {
    checksum += pinocchio::crba(model, data, s.q)(0, 0);
  });
  const double aba_ns = time_per_call(states, [&](const State &s) {
    checksum += pinocchio::aba(model, data, s.q, s.v, s.tau)[0];
  });
  if (!std::isfinite(checksum)) std::cerr << "warning: a result was not finite\n";

  std::printf("%s %.1f %.1f %.1f %d\n", name.c_str(), rnea_ns, crba_ns, aba_ns, (int)model.nv);
  return 0;
}
