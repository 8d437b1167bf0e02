#pragma once
// The physics a simulated bench was given, as its truth file names it (J, K_b, each friction
// term): one writer for the virtual bench and the emulated motor.
#include <nlohmann/json.hpp>

#include "spindown/bench.hpp"
#include "spindown/friction.hpp"

namespace spindown {

inline void write_physics_truth(nlohmann::json& t, const BenchParams& bench, const FrictionTerms& f) {
  t["inertia_kg_m2"] = bench.inertia_kg_m2;
  t["kb_v_s_per_rad"] = bench.kb_v_s_per_rad;
  t["c_v"] = f.viscous;
  t["c_c"] = f.coulomb;
  t["c_s"] = f.stribeck_static;
  t["w_s"] = f.stribeck_speed;
  t["c_w"] = f.windage;
}

}  // namespace spindown
