// Cost of one right-hand-side evaluation against the size of the mechanism: a planar chain of
// N links hanging from the ground, every joint revolute, with k of them clearance joints (the
// rest ideal). Reports ns per evaluation (median of repeats) so the growth with bodies and with
// clearance joints can be read off. The state is a fixed assembled pose, so every evaluation does
// the same work; a journal is pressed into its bearing so contact forces are computed.
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <string>
#include <vector>

#include "core/dynamics.hpp"
#include "io/model_loader.hpp"

namespace {

std::string chain_yaml(int n, int clearance_joints) {
  std::string y = "gravity: [0, -9.81]\nbodies:\n";
  for (int i = 0; i < n; ++i)
    y += "  l" + std::to_string(i) + ": {mass: 0.2, inertia: 1.0e-4, position: [" +
         std::to_string(0.05 + 0.1 * i) + ", 0], markers: {A: [-0.05, 0], B: [0.05, 0]}}\n";
  y += "clearance_defaults: {journal_radius: 9.5e-3, material: {youngs_modulus: 207e9, "
       "poisson_ratio: 0.3}, normal_law: lankarani_nikravesh, restitution: 0.9}\njoints:\n";
  for (int i = 0; i < n; ++i) {
    const std::string bearing = i == 0 ? "ground" : "l" + std::to_string(i - 1) + ".B";
    y += "  j" + std::to_string(i) + ": {type: revolute, journal: l" + std::to_string(i) +
         ".A, bearing: " + bearing + (i < clearance_joints ? ", clearance: 0.5e-3" : "") + "}\n";
  }
  y += "solver: {end_time: 0.01}\n";
  return y;
}

double ns_per_eval(int n, int k) {
  const lash::Model m = lash::load_model_text(chain_yaml(n, k), "chain.yaml").model;
  lash::Workspace ws(m);
  Eigen::VectorXd y = lash::initial_state(m, ws), ydot(ws.ny);
  if (k > 0) y[0] += 0.6e-3;  // the first journal into its bearing
  ws.contact.assign(ws.nc, {true});
  for (int i : ws.aux_impact) y[i] = 1.0;
  const int calls = std::max(2000, 200000 / n);
  std::vector<double> samples;
  for (int r = 0; r < 7; ++r) {
    const auto t0 = std::chrono::steady_clock::now();
    for (int i = 0; i < calls; ++i) lash::evaluate(m, ws, 0.0, y.data(), ydot.data());
    samples.push_back(std::chrono::duration<double, std::nano>(std::chrono::steady_clock::now() - t0).count() / calls);
  }
  std::sort(samples.begin(), samples.end());
  return samples[samples.size() / 2];
}

}  // namespace

int main() {
  std::printf("links N | constraint rows (all ideal) | ns/eval all ideal | ns/eval all clearance | ns/eval per clearance joint\n");
  for (int n : {2, 4, 8, 16, 32}) {
    const double ideal = ns_per_eval(n, 0), clear = ns_per_eval(n, n);
    std::printf("%7d | %27d | %17.0f | %21.0f | %27.1f\n", n, 2 * n, ideal, clear, clear / n);
  }
  std::printf("\nclearance joints k in a 16-link chain (the rest ideal):\n k | ns/eval\n");
  for (int k : {0, 1, 2, 4, 8, 16}) std::printf("%2d | %7.0f\n", k, ns_per_eval(16, k));
  return 0;
}
