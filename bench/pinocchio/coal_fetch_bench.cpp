// Pinocchio + coal collision micro-benchmark on Fetch: per-query median time (ns) of self
// distances (convex hulls, and the exact meshes as coal BVH models), self collision checks and
// robot-scene queries, with the method of
// pinocchio_bench.cpp (NSTATES seeded states per batch, WARMUP discarded batches, median of
// NBATCH batches, per-query time = batch time / NSTATES).
//
// Build and run: ./run.sh collision [FETCH_DIR] [SCENE.yaml]
//   coal_fetch_bench FETCH_DIR [SCENE.txt [SCENE_LABEL]]
// FETCH_DIR holds fetch_description/robots/fetch.urdf, fetch_description/meshes/*.STL and
// fetch.srdf; it is also the package directory that `package://fetch_description/...` resolves
// against. SCENE.txt is the flat file mbm_scene.py writes from a MotionBenchMaker scene YAML.
// Output: `robot query nq nv median_ns` lines ('#' lines are notes and sanity checks).
// Env: NBATCH, WARMUP (batch counts), VOXELS (target voxel count of the voxel scene, 0 = none),
// STATES (a file of Pinocchio-layout states, one per line, '#' lines skipped, as
// fetch_states.py writes: the states moma's `cargo bench --bench collision` times too; run.sh
// passes the repository's crates/moma/benches/data/fetch_states_pinocchio.txt). Without it,
// NSTATES seeded random states. With STATES the per-state verdicts of the in-collision
// checks are printed as '# verdicts QUERY 0101...' lines to compare with moma's.
//
// Model (the definitions of the collision reference set): fixed base (no root joint, base_link
// = world), every <collision> element of the URDF, each mesh replaced by the convex hull of its
// vertices (coal's qhull-based BVHModelBase::buildConvexHull), all 210 link pairs minus the
// SRDF's disabled ones (pinocchio::srdf::removeCollisionPairs). Narrow phase: coal's defaults,
// i.e. what a user of computeDistances / computeCollisions gets (printed below). Random states:
// revolute and prismatic joints uniform within the URDF limits, continuous joints uniform in
// [-pi, pi], seeded.

#include <pinocchio/algorithm/frames.hpp>
#include <pinocchio/algorithm/geometry.hpp>
#include <pinocchio/algorithm/joint-configuration.hpp>
#include <pinocchio/algorithm/kinematics.hpp>
#include <pinocchio/collision/collision.hpp>
#include <pinocchio/collision/distance.hpp>
#include <pinocchio/multibody/data.hpp>
#include <pinocchio/multibody/geometry.hpp>
#include <pinocchio/multibody/model.hpp>
#include <pinocchio/parsers/srdf.hpp>
#include <pinocchio/parsers/urdf.hpp>

#include <coal/BVH/BVH_model.h>
#include <coal/narrowphase/narrowphase_defaults.h>
#include <coal/octree.h>
#include <coal/shape/geometric_shapes.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <map>
#include <random>
#include <set>
#include <sstream>
#include <string>
#include <tuple>
#include <vector>

using pinocchio::Data;
using pinocchio::GeometryData;
using pinocchio::GeometryModel;
using pinocchio::GeometryObject;
using pinocchio::Model;
using Eigen::VectorXd;

static int NSTATES = 100;
static int NBATCH = 100;
static int WARMUP = 10;
static volatile double g_sink = 0.0;
static double g_last_min = 0.0;

template <class F>
static double median_ns_per_call(F &&f) {
  using clk = std::chrono::steady_clock;
  std::vector<double> per_call;
  per_call.reserve(NBATCH);
  for (int b = 0; b < WARMUP + NBATCH; ++b) {
    auto t0 = clk::now();
    for (int i = 0; i < NSTATES; ++i) f(i);
    auto t1 = clk::now();
    if (b >= WARMUP)
      per_call.push_back(std::chrono::duration<double, std::nano>(t1 - t0).count() / NSTATES);
  }
  g_last_min = *std::min_element(per_call.begin(), per_call.end());
  std::nth_element(per_call.begin(), per_call.begin() + per_call.size() / 2, per_call.end());
  return per_call[per_call.size() / 2];
}

// Replace every mesh of `geom` by its convex hull (the hull's triangles are kept, so coal's
// support function can walk the vertex neighbours).
static void meshes_to_hulls(GeometryModel &geom) {
  for (GeometryObject &g : geom.geometryObjects) {
    auto bvh = std::dynamic_pointer_cast<coal::BVHModelBase>(g.geometry);
    if (!bvh) continue;
    bvh->buildConvexHull(true, "Qt");
    g.geometry = bvh->convex;
  }
}

// Every pair of geometry objects (i < j), then the SRDF's <disable_collisions> removed.
static void all_pairs_minus_srdf(const Model &model, GeometryModel &geom, const std::string &srdf) {
  geom.removeAllCollisionPairs();
  for (std::size_t i = 0; i < geom.ngeoms; ++i)
    for (std::size_t j = i + 1; j < geom.ngeoms; ++j)
      geom.addCollisionPair(pinocchio::CollisionPair(i, j));
  if (!srdf.empty()) pinocchio::srdf::removeCollisionPairs(model, geom, srdf, false);
}

struct Prim {
  std::string kind, id;
  double p[3], quat[4], dims[3];
};

static std::vector<Prim> read_scene(const std::string &path) {
  std::vector<Prim> out;
  std::ifstream in(path);
  if (!in) {
    std::fprintf(stderr, "cannot read scene %s\n", path.c_str());
    std::exit(1);
  }
  std::string line;
  while (std::getline(in, line)) {
    if (line.empty() || line[0] == '#') continue;
    std::istringstream s(line);
    Prim p{};
    s >> p.kind >> p.id;
    for (double &x : p.p) s >> x;
    for (double &x : p.quat) s >> x;
    const int nd = p.kind == "box" ? 3 : p.kind == "cylinder" ? 2 : 1;
    for (int k = 0; k < nd; ++k) s >> p.dims[k];
    if (!s) {
      std::fprintf(stderr, "%s: bad line: %s\n", path.c_str(), line.c_str());
      std::exit(1);
    }
    out.push_back(p);
  }
  return out;
}

static pinocchio::SE3 prim_pose(const Prim &p) {
  Eigen::Quaterniond q(p.quat[3], p.quat[0], p.quat[1], p.quat[2]);
  q.normalize();
  return pinocchio::SE3(q.toRotationMatrix(), Eigen::Vector3d(p.p[0], p.p[1], p.p[2]));
}

static std::shared_ptr<coal::CollisionGeometry> prim_shape(const Prim &p) {
  if (p.kind == "box") return std::make_shared<coal::Box>(p.dims[0], p.dims[1], p.dims[2]);
  if (p.kind == "cylinder") return std::make_shared<coal::Cylinder>(p.dims[1], p.dims[0]);
  if (p.kind == "sphere") return std::make_shared<coal::Sphere>(p.dims[0]);
  std::fprintf(stderr, "unknown primitive %s\n", p.kind.c_str());
  std::exit(1);
}

// Is the point l, in primitive p's own frame, inside p?
static bool prim_contains_local(const Prim &p, const Eigen::Vector3d &l) {
  if (p.kind == "box")
    return std::abs(l[0]) <= 0.5 * p.dims[0] && std::abs(l[1]) <= 0.5 * p.dims[1] &&
           std::abs(l[2]) <= 0.5 * p.dims[2];
  if (p.kind == "cylinder")
    return std::abs(l[2]) <= 0.5 * p.dims[0] && l.head<2>().norm() <= p.dims[1];
  return l.norm() <= p.dims[0];
}

// Centres (i + 1/2) r of the grid cells of size r whose centre lies inside some primitive.
static std::vector<Eigen::Vector3d> voxelise(const std::vector<Prim> &scene, double r) {
  std::set<std::tuple<long, long, long>> keys;
  for (const Prim &p : scene) {
    const pinocchio::SE3 M = prim_pose(p);
    const Eigen::Vector3d half = p.kind == "box"        ? Eigen::Vector3d(p.dims[0], p.dims[1], p.dims[2]) * 0.5
                                 : p.kind == "cylinder" ? Eigen::Vector3d(p.dims[1], p.dims[1], 0.5 * p.dims[0])
                                                        : Eigen::Vector3d::Constant(p.dims[0]);
    const Eigen::Vector3d ext = M.rotation().cwiseAbs() * half;  // world AABB half extents
    long lo[3], hi[3];
    for (int k = 0; k < 3; ++k) {
      lo[k] = (long)std::floor((M.translation()[k] - ext[k]) / r) - 1;
      hi[k] = (long)std::ceil((M.translation()[k] + ext[k]) / r) + 1;
    }
    const Eigen::Matrix3d Rt = M.rotation().transpose();
    for (long i = lo[0]; i <= hi[0]; ++i)
      for (long j = lo[1]; j <= hi[1]; ++j)
        for (long k = lo[2]; k <= hi[2]; ++k) {
          const Eigen::Vector3d x((i + 0.5) * r, (j + 0.5) * r, (k + 0.5) * r);
          if (prim_contains_local(p, Rt * (x - M.translation()))) keys.insert({i, j, k});
        }
  }
  std::vector<Eigen::Vector3d> out;
  out.reserve(keys.size());
  for (auto &k : keys)
    out.emplace_back((std::get<0>(k) + 0.5) * r, (std::get<1>(k) + 0.5) * r, (std::get<2>(k) + 0.5) * r);
  return out;
}

// Seeded random states within the joint limits (continuous joints: angle in [-pi, pi]).
static std::vector<VectorXd> random_states(const Model &model, unsigned seed, int n) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> U(0.0, 1.0);
  std::vector<VectorXd> Q;
  for (int s = 0; s < n; ++s) {
    VectorXd q = pinocchio::neutral(model);
    for (pinocchio::JointIndex j = 1; j < (pinocchio::JointIndex)model.njoints; ++j) {
      const int iq = model.idx_qs[j], nqj = model.nqs[j], nvj = model.nvs[j];
      if (nqj == 2 && nvj == 1) {  // continuous: [cos, sin]
        const double th = -M_PI + 2 * M_PI * U(rng);
        q[iq] = std::cos(th);
        q[iq + 1] = std::sin(th);
      } else if (nqj == 1) {
        const double lo = model.lowerPositionLimit[iq], hi = model.upperPositionLimit[iq];
        q[iq] = lo + (hi - lo) * U(rng);
      } else {
        std::fprintf(stderr, "joint %s: unsupported type\n", model.names[j].c_str());
        std::exit(1);
      }
    }
    Q.push_back(q);
  }
  return Q;
}

// States from a text file: one Pinocchio-layout q per line ('#' lines skipped).
static std::vector<VectorXd> read_states(const Model &model, const std::string &path) {
  std::ifstream in(path);
  if (!in) {
    std::fprintf(stderr, "cannot read states %s\n", path.c_str());
    std::exit(1);
  }
  std::vector<VectorXd> Q;
  std::string line;
  while (std::getline(in, line)) {
    if (line.empty() || line[0] == '#') continue;
    std::istringstream s(line);
    VectorXd q(model.nq);
    for (int k = 0; k < model.nq; ++k) s >> q[k];
    if (!s) {
      std::fprintf(stderr, "%s: a state line with fewer than nq = %d numbers\n", path.c_str(), model.nq);
      std::exit(1);
    }
    Q.push_back(q);
  }
  if (Q.empty()) {
    std::fprintf(stderr, "%s: no state\n", path.c_str());
    std::exit(1);
  }
  return Q;
}

// MotionBenchMaker's default Fetch state (configs/robots/fetch.yaml: tucked arm, torso 0.1 m).
static VectorXd mbm_default_state(const Model &model) {
  const std::vector<std::pair<std::string, double>> js = {
      {"torso_lift_joint", 0.1},      {"bellows_joint", 0.05},       {"shoulder_pan_joint", 1.32},
      {"shoulder_lift_joint", 1.4},   {"upperarm_roll_joint", -0.2}, {"elbow_flex_joint", 1.72},
      {"forearm_roll_joint", 0.0},    {"wrist_flex_joint", 1.66},    {"wrist_roll_joint", 0.0},
      {"l_gripper_finger_joint", 0.05}, {"r_gripper_finger_joint", 0.05}};
  VectorXd q = pinocchio::neutral(model);
  for (auto &[name, val] : js) {
    if (!model.existJointName(name)) continue;
    const auto j = model.getJointId(name);
    const int iq = model.idx_qs[j];
    if (model.nqs[j] == 2) {
      q[iq] = std::cos(val);
      q[iq + 1] = std::sin(val);
    } else {
      q[iq] = val;
    }
  }
  return q;
}

static std::string pair_name(const GeometryModel &g, std::size_t k) {
  const auto &cp = g.collisionPairs[k];
  return g.geometryObjects[cp.first].name + "-" + g.geometryObjects[cp.second].name;
}

int main(int argc, char **argv) {
  if (argc < 2) {
    std::fprintf(stderr, "usage: %s FETCH_DIR [SCENE.txt [SCENE_LABEL]]\n", argv[0]);
    return 2;
  }
  if (const char *e = std::getenv("NBATCH")) NBATCH = std::max(1, std::atoi(e));
  if (const char *e = std::getenv("WARMUP")) WARMUP = std::max(0, std::atoi(e));
  long voxels_target = 100000;
  if (const char *e = std::getenv("VOXELS")) voxels_target = std::atol(e);
  const std::string dir = argv[1];
  const std::string urdf = dir + "/fetch_description/robots/fetch.urdf";
  const std::string srdf = dir + "/fetch.srdf";
  const std::string scene_path = argc > 2 ? argv[2] : "";
  const std::string scene_label = argc > 3 ? argv[3] : "scene";

  std::printf("# pinocchio %d.%d.%d  coal %s  NSTATES=%d NBATCH=%d WARMUP=%d\n", PINOCCHIO_MAJOR_VERSION,
              PINOCCHIO_MINOR_VERSION, PINOCCHIO_PATCH_VERSION, COAL_VERSION, NSTATES, NBATCH, WARMUP);
  {
    double l1 = 0, l5 = 0, l15 = 0;
    if (FILE *f = std::fopen("/proc/loadavg", "r")) {
      if (std::fscanf(f, "%lf %lf %lf", &l1, &l5, &l15) != 3) l1 = -1;
      std::fclose(f);
    }
    std::printf("# loadavg at start: %.2f %.2f %.2f (2-core machine; >2 means contention)\n", l1, l5, l15);
  }

  Model model;
  pinocchio::urdf::buildModel(urdf, model);  // fixed base
  Data data(model);
  const int nq = model.nq, nv = model.nv;

  GeometryModel geom_mesh;
  pinocchio::urdf::buildGeom(model, urdf, pinocchio::COLLISION, geom_mesh, std::vector<std::string>{dir});
  GeometryModel geom;  // same objects, meshes replaced by their convex hulls
  pinocchio::urdf::buildGeom(model, urdf, pinocchio::COLLISION, geom, std::vector<std::string>{dir});
  meshes_to_hulls(geom);
  const std::size_t npairs_all = geom.ngeoms * (geom.ngeoms - 1) / 2;
  all_pairs_minus_srdf(model, geom, srdf);
  all_pairs_minus_srdf(model, geom_mesh, srdf);
  GeometryData gdata(geom), gdata_mesh(geom_mesh);

  {
    const coal::DistanceRequest &dr = gdata.distanceRequests.at(0);
    const coal::CollisionRequest &cr = gdata.collisionRequests.at(0);
    std::printf("# fetch: nq %d nv %d, %zu collision objects, %zu pairs, %zu enabled after the SRDF\n", nq, nv,
                geom.ngeoms, npairs_all, geom.collisionPairs.size());
    std::printf("# narrow phase (coal defaults as Pinocchio's GeometryData sets them): GJK tol %g max_it %zu, "
                "EPA tol %g max_it %zu, distance gjk_tolerance %g, collision gjk_tolerance %g, "
                "cached GJK guess (warm start) %d, security margin %g\n",
                coal::GJK_DEFAULT_TOLERANCE, (std::size_t)dr.gjk_max_iterations, coal::EPA_DEFAULT_TOLERANCE,
                (std::size_t)dr.epa_max_iterations, dr.gjk_tolerance, cr.gjk_tolerance,
                (int)dr.enable_cached_gjk_guess, cr.security_margin);
  }

  const char *states_path = std::getenv("STATES");
  const std::vector<VectorXd> Q = states_path ? read_states(model, states_path) : random_states(model, 42, NSTATES);
  NSTATES = (int)Q.size();
  std::printf("# states: %s (%d)\n", states_path ? states_path : "seeded random", NSTATES);
  // One character per state: 1 if the query reports a collision.
  auto verdicts = [&](const char *what, auto &&collides) {
    std::string v;
    for (const VectorXd &q : Q) v += collides(q) ? '1' : '0';
    std::printf("# verdicts %s %s\n", what, v.c_str());
  };

  // Sanity checks against the collision reference set: MotionBenchMaker's tucked default state
  // overlaps torso_lift_link's hull (about -2.5 cm), and how many random states collide.
  {
    const VectorXd q0 = mbm_default_state(model);
    const std::size_t k = pinocchio::computeDistances(model, data, geom, gdata, q0);
    std::printf("# check default_state min_enabled_convex=%.9f pair=%s\n", gdata.distanceResults[k].min_distance,
                pair_name(geom, k).c_str());
    pinocchio::computeDistances(model, data, geom_mesh, gdata_mesh, q0);
    double dm = 1e9;
    for (auto &r : gdata_mesh.distanceResults) dm = std::min(dm, r.min_distance);
    std::printf("# check default_state min_enabled_mesh=%.9f\n", dm);
    double sum = 0;
    for (const VectorXd &q : Q) {
      const std::size_t k = pinocchio::computeDistances(model, data, geom, gdata, q);
      sum += gdata.distanceResults[k].min_distance;
    }
    std::printf("# check mean min self distance over the states %.9f\n", sum / NSTATES);
    int nc = 0, ncm = 0;
    for (const VectorXd &q : Q) {
      nc += pinocchio::computeCollisions(model, data, geom, gdata, q, true);
      ncm += pinocchio::computeCollisions(model, data, geom_mesh, gdata_mesh, q, true);
    }
    std::printf("# check random states in self-collision: hulls %d/%d, meshes %d/%d\n", nc, NSTATES, ncm, NSTATES);
    verdicts("self_collisions_first", [&](const VectorXd &q) {
      return pinocchio::computeCollisions(model, data, geom, gdata, q, true);
    });
  }

  std::printf("# robot query nq nv median_ns   ('# min' lines: fastest batch)\n");
  std::vector<std::string> mins;
  auto report = [&](const std::string &robot, const char *what, double ns) {
    std::printf("%s %s %d %d %.1f\n", robot.c_str(), what, nq, nv, ns);
    char buf[256];
    std::snprintf(buf, sizeof(buf), "# min %s %s %.1f", robot.c_str(), what, g_last_min);
    mins.push_back(buf);
    std::fflush(stdout);
  };

  // Placements of every state, precomputed for the queries timed without them.
  std::vector<std::vector<pinocchio::SE3>> OMG(NSTATES);
  for (int i = 0; i < NSTATES; ++i) {
    pinocchio::updateGeometryPlacements(model, data, geom, gdata, Q[i]);
    OMG[i].assign(gdata.oMg.begin(), gdata.oMg.end());
  }

  report("fetch", "self_placements", median_ns_per_call([&](int i) {
           pinocchio::updateGeometryPlacements(model, data, geom, gdata, Q[i]);
           g_sink = g_sink + gdata.oMg.back().translation()[0];
         }));
  report("fetch", "self_distances", median_ns_per_call([&](int i) {
           const std::size_t k = pinocchio::computeDistances(model, data, geom, gdata, Q[i]);
           g_sink = g_sink + gdata.distanceResults[k].min_distance;
         }));
  // Placements copied in (21 SE3, a few tens of ns), then the 76 pair distances alone.
  report("fetch", "self_distances_noplacement", median_ns_per_call([&](int i) {
           std::copy(OMG[i].begin(), OMG[i].end(), gdata.oMg.begin());
           const std::size_t k = pinocchio::computeDistances(geom, gdata);
           g_sink = g_sink + gdata.distanceResults[k].min_distance;
         }));
  report("fetch", "self_collisions_first", median_ns_per_call([&](int i) {
           g_sink = g_sink + pinocchio::computeCollisions(model, data, geom, gdata, Q[i], true);
         }));
  report("fetch", "self_collisions_all", median_ns_per_call([&](int i) {
           g_sink = g_sink + pinocchio::computeCollisions(model, data, geom, gdata, Q[i], false);
         }));
  report("fetch", "self_collisions_first_mesh", median_ns_per_call([&](int i) {
           g_sink = g_sink + pinocchio::computeCollisions(model, data, geom_mesh, gdata_mesh, Q[i], true);
         }));
  {
    // The exact meshes' distances (coal's BVH models, OBBRSS) on the same 76 pairs: tens of
    // milliseconds per state, so NBATCH_SLOW (default 5) batches after one warm-up batch.
    double sum = 0;
    for (const VectorXd &q : Q) {
      pinocchio::computeDistances(model, data, geom_mesh, gdata_mesh, q);
      double dm = 1e9;
      for (auto &r : gdata_mesh.distanceResults) dm = std::min(dm, r.min_distance);
      sum += dm;
    }
    std::printf("# check mean min enabled mesh distance over the states %.9f\n", sum / NSTATES);
    const int nb = NBATCH, wu = WARMUP;
    NBATCH = 5;
    if (const char *e = std::getenv("NBATCH_SLOW")) NBATCH = std::max(1, std::atoi(e));
    WARMUP = 1;
    report("fetch", "self_distances_mesh", median_ns_per_call([&](int i) {
             pinocchio::computeDistances(model, data, geom_mesh, gdata_mesh, Q[i]);
             g_sink = g_sink + gdata_mesh.distanceResults[0].min_distance;
           }));
    NBATCH = nb;
    WARMUP = wu;
  }

  if (!scene_path.empty()) {
    const std::vector<Prim> scene = read_scene(scene_path);
    // Robot hulls + the scene's primitives (attached to the universe); pairs: link x object.
    GeometryModel gs;
    for (const GeometryObject &g : geom.geometryObjects) gs.addGeometryObject(g);
    const std::size_t nrobot = gs.ngeoms;
    for (std::size_t k = 0; k < scene.size(); ++k)
      gs.addGeometryObject(GeometryObject(scene[k].id + "_" + std::to_string(k), 0, 0, prim_pose(scene[k]),
                                          prim_shape(scene[k])));
    for (std::size_t i = 0; i < nrobot; ++i)
      for (std::size_t j = nrobot; j < gs.ngeoms; ++j) gs.addCollisionPair(pinocchio::CollisionPair(i, j));
    GeometryData gsd(gs);
    const std::string label = "fetch+" + scene_label;
    int nc = 0;
    for (const VectorXd &q : Q) nc += pinocchio::computeCollisions(model, data, gs, gsd, q, true);
    std::printf("# %s: %zu primitives, %zu link-object pairs, random states in collision %d/%d\n", label.c_str(),
                scene.size(), gs.collisionPairs.size(), nc, NSTATES);
    verdicts("scene_collisions_first", [&](const VectorXd &q) {
      return pinocchio::computeCollisions(model, data, gs, gsd, q, true);
    });
    {
      double sum = 0;
      for (const VectorXd &q : Q) {
        const std::size_t k = pinocchio::computeDistances(model, data, gs, gsd, q);
        sum += gsd.distanceResults[k].min_distance;
      }
      std::printf("# check %s mean min scene distance over the states %.9f\n", label.c_str(), sum / NSTATES);
    }
    {
      const std::size_t k = pinocchio::computeDistances(model, data, gs, gsd, mbm_default_state(model));
      std::printf("# check %s default_state min_distance=%.9f pair=%s\n", label.c_str(),
                  gsd.distanceResults[k].min_distance, pair_name(gs, k).c_str());
    }
    report(label, "scene_distances", median_ns_per_call([&](int i) {
             const std::size_t k = pinocchio::computeDistances(model, data, gs, gsd, Q[i]);
             g_sink = g_sink + gsd.distanceResults[k].min_distance;
           }));
    report(label, "scene_collisions_first", median_ns_per_call([&](int i) {
             g_sink = g_sink + pinocchio::computeCollisions(model, data, gs, gsd, Q[i], true);
           }));

    if (voxels_target > 0) {
      // The scene's primitives voxelised: the cell size r is bisected so that the number of
      // cells whose centre (i + 1/2) r lies inside a primitive is as close to the target as
      // the grid allows; the cells become one coal::OcTree (octomap) of resolution r.
      // (Thin plates take a whole number of cell layers, so the count jumps with r; the
      // closest count found is kept and printed.)
      double lo = 0.002, hi = 0.2, r = 0.01;
      std::vector<Eigen::Vector3d> cells;
      for (int it = 0; it < 40; ++it) {
        const double rr = 0.5 * (lo + hi);
        std::vector<Eigen::Vector3d> c = voxelise(scene, rr);
        const long n = (long)c.size();
        if (cells.empty() || std::labs((long)c.size() - voxels_target) < std::labs((long)cells.size() - voxels_target)) {
          cells.swap(c);
          r = rr;
        }
        if ((long)cells.size() == voxels_target) break;
        if (n > voxels_target) lo = rr;
        else hi = rr;
        if (hi - lo < 1e-7) break;
      }
      Eigen::Matrix<double, Eigen::Dynamic, 3> pts((Eigen::Index)cells.size(), 3);
      for (std::size_t k = 0; k < cells.size(); ++k) pts.row((Eigen::Index)k) = cells[k].transpose();
      coal::OcTreePtr_t tree = coal::makeOctree(pts, r);
      GeometryModel gv;
      for (const GeometryObject &g : geom.geometryObjects) gv.addGeometryObject(g);
      gv.addGeometryObject(GeometryObject("voxels", 0, 0, pinocchio::SE3::Identity(), tree));
      for (std::size_t i = 0; i < nrobot; ++i) gv.addCollisionPair(pinocchio::CollisionPair(i, nrobot));
      GeometryData gvd(gv);
      const std::string vlabel = "fetch+" + scene_label + "_voxels";
      int ncv = 0;
      for (const VectorXd &q : Q) ncv += pinocchio::computeCollisions(model, data, gv, gvd, q, true);
      std::printf("# %s: %zu voxels of %.9f m (coal::OcTree, %zu octree leaves), %zu link-octree pairs, random "
                  "states in collision %d/%d\n",
                  vlabel.c_str(), cells.size(), r, (std::size_t)tree->getTree()->getNumLeafNodes(),
                  gv.collisionPairs.size(), ncv, NSTATES);
      verdicts("voxel_collisions_first", [&](const VectorXd &q) {
        return pinocchio::computeCollisions(model, data, gv, gvd, q, true);
      });
      report(vlabel, "voxel_collisions_first", median_ns_per_call([&](int i) {
               g_sink = g_sink + pinocchio::computeCollisions(model, data, gv, gvd, Q[i], true);
             }));
      try {
        // Slow (milliseconds): fewer batches, NBATCH_SLOW (default 5) after one warm-up batch.
        const int nb = NBATCH, wu = WARMUP;
        NBATCH = 5;
        if (const char *e = std::getenv("NBATCH_SLOW")) NBATCH = std::max(1, std::atoi(e));
        WARMUP = 1;
        report(vlabel, "voxel_distances", median_ns_per_call([&](int i) {
                 const std::size_t k = pinocchio::computeDistances(model, data, gv, gvd, Q[i]);
                 g_sink = g_sink + gvd.distanceResults[k].min_distance;
               }));
        NBATCH = nb;
        WARMUP = wu;
      } catch (const std::exception &e) {
        std::printf("# %s voxel_distances not available: %s\n", vlabel.c_str(), e.what());
      }
    }
  }
  for (const auto &m : mins) std::printf("%s\n", m.c_str());
  std::printf("# sink %g\n", (double)g_sink);
  return 0;
}
