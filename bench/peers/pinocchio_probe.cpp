// Pinocchio's side of bench/peers.py: RNEA, CRBA and ABA on URDF robots, and the analytical
// derivatives of RNEA and ABA (computeRNEADerivatives, computeABADerivatives), timed on request.
//
//   pinocchio_probe NAME=ROBOT.urdf...
//
// Loads every robot (fixed base, gravity 9.80665 m/s^2 along -z as in lsdc's URDF import),
// draws 256 states per robot with a fixed seed (each coordinate uniform within its joint limits
// when both are finite, else in [-pi, pi]; v, a and tau uniform in [-1, 1]), prints
//   ready NAME/rnea NAME/crba NAME/aba NAME/rnea_derivatives NAME/aba_derivatives ...
// then answers each line `CASE CALLS` of its standard input with the CPU time, in seconds, that
// this thread spent on CALLS calls of CASE cycled over the states (CLOCK_THREAD_CPUTIME_ID: the
// time the shared machine gave to other programs is left out). The driver alternates these
// batches with lsdc's, which answers the same protocol (benches/peers.rs).
//
// Every call uses Pinocchio's default arguments (Convention::LOCAL for crba and aba; crba fills
// the upper triangle only, as Pinocchio does; computeRNEADerivatives gives dtau/dq, dtau/dv and
// the mass matrix as dtau/da, computeABADerivatives ddq/dq, ddq/dv and Minv = ddq/dtau). Each
// result feeds a checksum so no call can be optimised away.

#include <time.h>

#include <cmath>
#include <cstdio>
#include <iostream>
#include <map>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include <pinocchio/algorithm/aba-derivatives.hpp>
#include <pinocchio/algorithm/aba.hpp>
#include <pinocchio/algorithm/crba.hpp>
#include <pinocchio/algorithm/joint-configuration.hpp>
#include <pinocchio/algorithm/rnea-derivatives.hpp>
#include <pinocchio/algorithm/rnea.hpp>
#include <pinocchio/multibody.hpp>
#include <pinocchio/parsers/urdf.hpp>

namespace {

using Vector = Eigen::VectorXd;

struct State {
  Vector q, v, a, tau;
};

struct Robot {
  pinocchio::Model model;
  pinocchio::Data data;
  std::vector<State> states;
};

double thread_seconds() {
  timespec t;
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t);
  return (double)t.tv_sec + 1e-9 * (double)t.tv_nsec;
}

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
  }
  return q;
}

Vector uniform_vector(int n, std::mt19937_64 &rng) {
  std::uniform_real_distribution<double> dist(-1.0, 1.0);
  Vector x(n);
  for (int i = 0; i < n; ++i) x[i] = dist(rng);
  return x;
}

}  // namespace

int main(int argc, char **argv) {
  std::map<std::string, Robot> robots;
  std::string ready = "ready";
  for (int k = 1; k < argc; ++k) {
    const std::string arg = argv[k];
    const auto equal = arg.find('=');
    if (equal == std::string::npos) {
      std::cerr << "usage: " << argv[0] << " NAME=ROBOT.urdf...\n";
      return 2;
    }
    const std::string name = arg.substr(0, equal), path = arg.substr(equal + 1);
    pinocchio::Model model;
    try {
      pinocchio::urdf::buildModel(path, model);
    } catch (const std::exception &e) {
      std::cerr << "error: Pinocchio cannot read `" << path << "`: " << e.what() << "\n";
      return 1;
    }
    model.gravity.linear(Eigen::Vector3d(0.0, 0.0, -9.80665));
    Robot robot{model, pinocchio::Data(model), {}};
    std::mt19937_64 rng(20240611);
    for (int s = 0; s < 256; ++s)
      robot.states.push_back(State{random_configuration(model, rng), uniform_vector(model.nv, rng),
                                   uniform_vector(model.nv, rng), uniform_vector(model.nv, rng)});
    robots.emplace(name, std::move(robot));
    for (const char *algorithm : {"rnea", "crba", "aba", "rnea_derivatives", "aba_derivatives"})
      ready += " " + name + "/" + algorithm;
  }
  std::printf("%s\n", ready.c_str());
  std::fflush(stdout);

  double checksum = 0.0;
  std::string line;
  while (std::getline(std::cin, line)) {
    std::istringstream words(line);
    std::string name_and_case;
    long calls = 0;
    if (!(words >> name_and_case >> calls) || calls <= 0) {
      std::printf("error: expected `CASE CALLS`, got `%s`\n", line.c_str());
      std::fflush(stdout);
      continue;
    }
    const auto slash = name_and_case.rfind('/');
    const auto found = robots.find(name_and_case.substr(0, slash));
    const std::string algorithm = slash == std::string::npos ? "" : name_and_case.substr(slash + 1);
    if (found == robots.end() || (algorithm != "rnea" && algorithm != "crba" && algorithm != "aba" &&
                                  algorithm != "rnea_derivatives" && algorithm != "aba_derivatives")) {
      std::printf("error: no case `%s`\n", name_and_case.c_str());
      std::fflush(stdout);
      continue;
    }
    Robot &r = found->second;
    const std::size_t n = r.states.size();
    const double start = thread_seconds();
    if (algorithm == "rnea") {
      for (long i = 0; i < calls; ++i) {
        const State &s = r.states[i % n];
        checksum += pinocchio::rnea(r.model, r.data, s.q, s.v, s.a)[0];
      }
    } else if (algorithm == "crba") {
      for (long i = 0; i < calls; ++i) checksum += pinocchio::crba(r.model, r.data, r.states[i % n].q)(0, 0);
    } else if (algorithm == "aba") {
      for (long i = 0; i < calls; ++i) {
        const State &s = r.states[i % n];
        checksum += pinocchio::aba(r.model, r.data, s.q, s.v, s.tau)[0];
      }
    } else if (algorithm == "rnea_derivatives") {
      for (long i = 0; i < calls; ++i) {
        const State &s = r.states[i % n];
        pinocchio::computeRNEADerivatives(r.model, r.data, s.q, s.v, s.a);
        checksum += r.data.dtau_dq(0, 0) + r.data.dtau_dv(0, 0);
      }
    } else {
      for (long i = 0; i < calls; ++i) {
        const State &s = r.states[i % n];
        pinocchio::computeABADerivatives(r.model, r.data, s.q, s.v, s.tau);
        checksum += r.data.ddq_dq(0, 0) + r.data.ddq_dv(0, 0) + r.data.Minv(0, 0);
      }
    }
    const double seconds = thread_seconds() - start;
    if (!std::isfinite(checksum)) std::cerr << "warning: a result was not finite\n";
    std::printf("%.9e\n", seconds);
    std::fflush(stdout);
  }
  return 0;
}
