// OMPL's sampling planners on the detour scenarios exported by planners.py --export (issue 17):
// the same inflated grid as the state-validity check (a state is valid on a free cell), R^2.
// Not built by catkin (OMPL is not a dependency of RoboDog): bench/run compiles it when
// `pkg-config ompl` finds libompl-dev. Prints one JSON line per planner and scenario.
#include <ompl/base/spaces/RealVectorStateSpace.h>
#include <ompl/geometric/SimpleSetup.h>
#include <ompl/geometric/planners/prm/PRM.h>
#include <ompl/geometric/planners/rrt/RRTConnect.h>
#include <ompl/geometric/planners/rrt/RRTstar.h>
#include <ompl/util/Console.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <fstream>
#include <iostream>
#include <string>
#include <vector>

namespace ob = ompl::base;
namespace og = ompl::geometric;

struct Grid {
  int w = 0, h = 0;
  double x0 = 0, y0 = 0, res = 0, sx = 0, sy = 0, gx = 0, gy = 0;
  std::vector<std::string> rows;
  bool free(double x, double y) const {
    const int c = static_cast<int>(std::floor((x - x0) / res));
    const int r = static_cast<int>(std::floor((y - y0) / res));
    return c >= 0 && r >= 0 && c < w && r < h && rows[r][c] == '0';
  }
};

static double clearance(const og::PathGeometric& path, const std::vector<std::pair<double, double>>& obs) {
  double best = 1e9;
  for (std::size_t i = 0; i + 1 < path.getStateCount(); ++i) {
    const auto* a = path.getState(i)->as<ob::RealVectorStateSpace::StateType>();
    const auto* b = path.getState(i + 1)->as<ob::RealVectorStateSpace::StateType>();
    for (int k = 0; k <= 40; ++k) {
      const double u = k / 40.0;
      const double x = a->values[0] + u * (b->values[0] - a->values[0]);
      const double y = a->values[1] + u * (b->values[1] - a->values[1]);
      for (const auto& o : obs) best = std::min(best, std::hypot(o.first - x, o.second - y));
    }
  }
  return best;
}

int main(int argc, char** argv) {
  if (argc < 3) {
    std::cerr << "usage: ompl_compare DIR SCENARIO..." << std::endl;
    return 2;
  }
  ompl::msg::setLogLevel(ompl::msg::LOG_NONE);
  const std::string dir = argv[1];
  for (int s = 2; s < argc; ++s) {
    const std::string name = argv[s];
    Grid g;
    std::ifstream in(dir + "/" + name + ".grid");
    in >> g.w >> g.h >> g.x0 >> g.y0 >> g.res >> g.sx >> g.sy >> g.gx >> g.gy;
    g.rows.resize(g.h);
    for (int r = 0; r < g.h; ++r) in >> g.rows[r];
    std::vector<std::pair<double, double>> obs;
    std::ifstream oin(dir + "/" + name + ".obstacles");
    double ox, oy;
    while (oin >> ox >> oy) obs.emplace_back(ox, oy);
    for (const std::string planner :
         {"RRTConnect+simplify", "RRTstar(0.5 s)+simplify", "PRM(0.5 s)+simplify"}) {
      std::vector<double> times, lengths, clear;
      int solved = 0;
      for (int run = 0; run < 20; ++run) {
        auto space = std::make_shared<ob::RealVectorStateSpace>(2);
        ob::RealVectorBounds bounds(2);
        bounds.setLow(0, g.x0);
        bounds.setHigh(0, g.x0 + g.w * g.res);
        bounds.setLow(1, g.y0);
        bounds.setHigh(1, g.y0 + g.h * g.res);
        space->setBounds(bounds);
        og::SimpleSetup ss(space);
        ss.setStateValidityChecker([&g](const ob::State* st) {
          const auto* v = st->as<ob::RealVectorStateSpace::StateType>();
          return g.free(v->values[0], v->values[1]);
        });
        ss.getSpaceInformation()->setStateValidityCheckingResolution(g.res / (g.w * g.res) / 2.0);
        ob::ScopedState<> start(space), goal(space);
        start[0] = g.sx;
        start[1] = g.sy;
        goal[0] = g.gx;
        goal[1] = g.gy;
        ss.setStartAndGoalStates(start, goal);
        double budget = 1.0;
        if (planner[0] == 'R' && planner[3] == 'C') {
          ss.setPlanner(std::make_shared<og::RRTConnect>(ss.getSpaceInformation()));
        } else if (planner[0] == 'R') {
          ss.setPlanner(std::make_shared<og::RRTstar>(ss.getSpaceInformation()));
          budget = 0.5;
        } else {
          ss.setPlanner(std::make_shared<og::PRM>(ss.getSpaceInformation()));
          budget = 0.5;
        }
        const auto t0 = std::chrono::steady_clock::now();
        const bool ok = ss.solve(budget) == ob::PlannerStatus::EXACT_SOLUTION;
        if (ok) ss.simplifySolution(0.2);
        const double dt = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
        if (!ok) continue;
        ++solved;
        times.push_back(dt);
        lengths.push_back(ss.getSolutionPath().length() / std::hypot(g.gx - g.sx, g.gy - g.sy));
        clear.push_back(clearance(ss.getSolutionPath(), obs));
      }
      std::sort(times.begin(), times.end());
      std::sort(lengths.begin(), lengths.end());
      std::sort(clear.begin(), clear.end());
      auto mid = [](const std::vector<double>& v) { return v.empty() ? -1.0 : v[v.size() / 2]; };
      auto hi = [](const std::vector<double>& v) { return v.empty() ? -1.0 : v.back(); };
      auto lo = [](const std::vector<double>& v) { return v.empty() ? -1.0 : v.front(); };
      std::cout << "{\"planner\": \"OMPL " << planner << "\", \"scenario\": \"" << name
                << "\", \"solved\": " << solved << ", \"runs\": 20, \"time_ms_p50\": " << 1000 * mid(times)
                << ", \"length_over_direct_p50\": " << mid(lengths)
                << ", \"length_over_direct_max\": " << hi(lengths)
                << ", \"min_clearance_m_min\": " << lo(clear) << "}" << std::endl;
    }
  }
  return 0;
}
