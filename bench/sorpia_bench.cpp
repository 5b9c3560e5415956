// sorpia-bench: times each phase of sorpia's three capabilities on mesh files
// and generated meshes: interpolation (read, topology, operator, solve, write,
// with the streaming floor of a sweep and the peak memory), fair
// interpolation (sorpia::fair_interpolate: plain solve, refinement, K, setup,
// solve) and approximation (sorpia::approximate of the mesh's vertices by a
// decimated cage: footpoints, rows, normal equations, solve, report). Links
// the C++ core only.
//
//   sorpia-bench icosphere:8 torus:1000x1000 --method sor,gs,wpia --repeat 5
//   sorpia-bench bunny.ply --write /tmp/out --json
//   sorpia-bench --task fair irregular:3000 --levels 2
//   sorpia-bench --task approximate bunny.obj --cage-vertices 400
#include <malloc.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <functional>
#include <iostream>
#include <optional>
#include <random>
#include <sstream>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

#include "sorpia/approximation.hpp"
#include "sorpia/cage.hpp"
#include "sorpia/errors.hpp"
#include "sorpia/fair_interpolation.hpp"
#include "sorpia/interpolator.hpp"
#include "sorpia/io.hpp"
#include "sorpia/limit.hpp"
#include "sorpia/limit_masks.hpp"
#include "sorpia/limit_operator.hpp"
#include "sorpia/shapes.hpp"
#include "sorpia/solvers.hpp"
#include "sorpia/topology.hpp"

namespace {

const char* const kUsage = R"(usage: sorpia-bench [options] MESH [MESH ...]

MESH is a mesh file (.obj .off .ply .stl) or a generated mesh:
  icosphere:L        sphere, 10*4^L + 2 vertices (L = 0..10; 8 gives 655k)
  torus:NUxNV        closed, every vertex of valence 6 (1000x1000 gives 1M)
  irregular:N[:SEED] closed, about N vertices, valences 3..12
  grid:NUxNV         open patch with boundary and two one-face corners
  pole:N             disk around one vertex of valence N
  quadtorus:NUxNV    the torus as quads, every vertex of valence 4
  quadgrid:NUxNV     the grid as quads
  quads:N[:SEED]     closed quad mesh, about N vertices, valences 3..12
                     (irregular:N/6 with each triangle split into 3 quads)
  polygons:NUxNV[:SEED]  the quad torus with triangles, pentagons, hexagons

options:
  --task NAME        interpolate (default), fair or approximate
  --method LIST      comma-separated: auto sor gs pia wpia cg hss whss gmres
                     cgls, or none (time topology and operator only);
                     default sor
  --tol X            stop when E_k/E_0 < X (default 1e-10)
  --max-iter N       default 1000
  --omega W          omega for sor: a number in (0, 2), auto or young (default: auto)
  --threads N        threads sweeping at once for sor and gs (default 1; the
                     other methods always run on one thread)
  --two-pass         sor/gs: E_k by a separate residual pass after each sweep
                     (the reference) instead of inside the sweep
  --boundary RULE    edge-and-corner (default) or edge-only
  --scheme NAME      loop (default; triangles only) or catmull-clark
  --triangulate      split polygons of mesh files into triangles
  --tags             use the OpenSubdiv tags (t lines) of OBJ files: creases,
                     corners, holes (their interpolateboundary is left to
                     --boundary)
  --creases S[:X]    tag every edge with probability S in [0, 1] (a fixed
                     random draw) as a crease of sharpness X (default inf;
                     added to the file's tags)
  --write DIR        write the control vertices to DIR/<mesh>.<method>.ply
                     (binary PLY; --format obj|off|ply-ascii for text)
  --repeat N         run everything N times, report medians (default 1)
  --json             print JSON instead of a table
  -h, --help         this text

fair (every vertex a target; the plain solve with --method's first, --tol
and --max-iter; --threads caps K and the products with it):
  --levels N         refinement levels (default 1)
  --membrane X       the membrane weight beside the thin plate's 1 (default 0)
  --fair-tol X       the energy's stop rule (default 1e-6)
approximate (the mesh's vertices fitted by the mesh decimated, the cage
split into quads under catmull-clark):
  --cage-vertices N  the cage's vertices (default: 2% of the mesh's, at least 50)
  --iterations N     updates at most (default 10)
  --fairness X       the fairness weight (default 3e-4)
  --update NAME      cg (default) or lspia (point distance, tangential 1)

Times are wall-clock seconds. "floor" is one plain streaming pass
over the arrays a sweep reads and writes (the operator, V0 as 3 doubles
and V as 4 doubles a vertex); sweep/floor = (solve seconds per
iteration) / floor. Peak memory is the process's VmHWM for that mesh;
B/vertex is that peak above the resident size once the input arrays exist.
)";

struct Usage : std::runtime_error {
  using std::runtime_error::runtime_error;
};

enum class Task { Interpolate, Fair, Approximate };

struct Options {
  Task task = Task::Interpolate;
  std::vector<std::string> meshes;
  std::vector<std::string> methods{"sor"};
  double tol = 1e-10;
  int max_iter = 1000;
  sorpia::OmegaRule omega_rule = sorpia::OmegaRule::Auto;
  double omega = NAN;
  int threads = 1;
  bool two_pass = false;
  sorpia::Boundary boundary = sorpia::Boundary::EdgeAndCorner;
  sorpia::Scheme scheme = sorpia::Scheme::Loop;
  bool triangulate = false;
  bool file_tags = false;
  double crease_share = 0.0, crease_sharpness = sorpia::kInfiniteSharpness;
  std::string write_dir, format = "ply";
  int repeat = 1;
  bool json = false;
  // fair
  int levels = 1;
  double membrane = 0.0, fair_tol = 1e-6;
  // approximate
  int cage_vertices = 0;  // 0: 2% of the mesh's, at least 50
  int iterations = 10;
  double fairness = 3e-4;
  sorpia::ApproximationUpdate update = sorpia::ApproximationUpdate::CG;
};

double to_double(const std::string& flag, const std::string& s) {
  try {
    std::size_t used = 0;
    const double x = std::stod(s, &used);
    if (used == s.size() && std::isfinite(x)) return x;
  } catch (const std::exception&) {
  }
  throw Usage(flag + " needs a number, got '" + s + "'");
}

int to_int(const std::string& flag, const std::string& s, int lo) {
  try {
    std::size_t used = 0;
    const long x = std::stol(s, &used);
    if (used == s.size() && x >= lo && x <= 1000000000) return static_cast<int>(x);
  } catch (const std::exception&) {
  }
  throw Usage(flag + " needs an integer >= " + std::to_string(lo) + ", got '" + s + "'");
}

std::vector<std::string> split(const std::string& s, char sep) {
  std::vector<std::string> out;
  std::stringstream in(s);
  for (std::string part; std::getline(in, part, sep);) out.push_back(part);
  return out;
}

Options parse(int argc, char** argv) {
  Options o;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    auto value = [&]() -> std::string {
      if (i + 1 >= argc) throw Usage(a + " needs a value");
      return argv[++i];
    };
    if (a == "-h" || a == "--help") {
      std::cout << kUsage;
      std::exit(0);
    } else if (a == "--task") {
      const std::string t = value();
      if (t == "interpolate") o.task = Task::Interpolate;
      else if (t == "fair") o.task = Task::Fair;
      else if (t == "approximate") o.task = Task::Approximate;
      else throw Usage("--task: interpolate, fair or approximate, got '" + t + "'");
    } else if (a == "--levels") {
      o.levels = to_int(a, value(), 1);
    } else if (a == "--membrane") {
      o.membrane = to_double(a, value());
    } else if (a == "--fair-tol") {
      o.fair_tol = to_double(a, value());
    } else if (a == "--cage-vertices") {
      o.cage_vertices = to_int(a, value(), 4);
    } else if (a == "--iterations") {
      o.iterations = to_int(a, value(), 1);
    } else if (a == "--fairness") {
      o.fairness = to_double(a, value());
    } else if (a == "--update") {
      const std::string u = value();
      if (u != "cg" && u != "lspia") throw Usage("--update: cg or lspia, got '" + u + "'");
      o.update = u == "cg" ? sorpia::ApproximationUpdate::CG : sorpia::ApproximationUpdate::LSPIA;
    } else if (a == "--method") {
      o.methods = split(value(), ',');
      for (const auto& m : o.methods)
        if (m != "none") try {
            sorpia::parse_method(m);
          } catch (const sorpia::ParameterError& e) {
            throw Usage(std::string("--method: ") + e.what());
          }
    } else if (a == "--tol") {
      o.tol = to_double(a, value());
      if (!(o.tol > 0 && o.tol < 1)) throw Usage("--tol must be in (0, 1)");
    } else if (a == "--max-iter") {
      o.max_iter = to_int(a, value(), 1);
    } else if (a == "--omega") {
      try {  // the library's own parsing and check, as for Python and the sorpia command
        sorpia::SolveOptions sor;
        sorpia::parse_omega(value(), sor);
        sorpia::check_options(sor);
        o.omega_rule = sor.omega_rule;
        o.omega = sor.omega;
      } catch (const sorpia::ParameterError& e) {
        throw Usage(std::string("--omega: ") + e.what());
      }
    } else if (a == "--threads") {
      o.threads = to_int(a, value(), 1);
      if (o.threads > sorpia::max_threads) throw Usage("--threads must be at most " + std::to_string(sorpia::max_threads));
    } else if (a == "--two-pass") {
      o.two_pass = true;
    } else if (a == "--boundary") {
      try {
        o.boundary = sorpia::parse_boundary(value());
      } catch (const sorpia::ParameterError& e) {
        throw Usage(std::string("--boundary: ") + e.what());
      }
    } else if (a == "--scheme") {
      try {
        o.scheme = sorpia::parse_scheme(value());
      } catch (const sorpia::ParameterError& e) {
        throw Usage(std::string("--scheme: ") + e.what());
      }
    } else if (a == "--tags") {
      o.file_tags = true;
    } else if (a == "--creases") {
      const auto parts = split(value(), ':');
      if (parts.empty() || parts.size() > 2) throw Usage("--creases: SHARE or SHARE:SHARPNESS");
      o.crease_share = to_double("--creases", parts[0]);
      if (!(o.crease_share >= 0.0 && o.crease_share <= 1.0)) throw Usage("--creases: SHARE must be in [0, 1]");
      if (parts.size() == 2)
        o.crease_sharpness = parts[1] == "inf" ? sorpia::kInfiniteSharpness : to_double("--creases", parts[1]);
      if (!(o.crease_sharpness >= 0.0)) throw Usage("--creases: SHARPNESS must be >= 0 or inf");
    } else if (a == "--triangulate") {
      o.triangulate = true;
    } else if (a == "--write") {
      o.write_dir = value();
    } else if (a == "--format") {
      o.format = value();
      if (o.format != "ply" && o.format != "ply-ascii" && o.format != "obj" && o.format != "off")
        throw Usage("--format: ply, ply-ascii, obj or off");
    } else if (a == "--repeat") {
      o.repeat = to_int(a, value(), 1);
    } else if (a == "--json") {
      o.json = true;
    } else if (!a.empty() && a[0] == '-') {
      throw Usage("unknown option " + a);
    } else {
      o.meshes.push_back(a);
    }
  }
  if (o.meshes.empty()) throw Usage("no mesh given");
  return o;
}

// ---- meshes ------------------------------------------------------------------

bool is_generated(const std::string& spec) { return spec.find(':') != std::string::npos && spec.find('.') == std::string::npos; }

// "torus:1000x1000" -> {1000, 1000}
std::vector<int> spec_numbers(const std::string& spec, char sep, std::size_t lo, std::size_t hi) {
  const auto parts = split(spec.substr(spec.find(':') + 1), sep);
  if (parts.size() < lo || parts.size() > hi) throw Usage("bad mesh '" + spec + "'");
  std::vector<int> out;
  for (const auto& p : parts) out.push_back(to_int(spec, p, 0));
  return out;
}

// A mesh: triangles without counts take Topology's triangle path (exactly
// as before polygons existed), any other mesh its polygon path with a count
// per face.
struct BenchMesh {
  sorpia::Mesh mesh;
  BenchMesh(sorpia::Mesh m) : mesh(std::move(m)) {
    if (mesh.uniform() && !mesh.all_triangles()) mesh.face_vertex_counts = mesh.counts();
  }
  bool polygons() const { return !mesh.all_triangles(); }
  const std::vector<double>& vertices() const { return mesh.vertices; }
  std::size_t n_vertices() const { return mesh.n_vertices(); }
  std::size_t n_faces() const { return mesh.n_faces(); }
};

BenchMesh generate(const std::string& spec);

BenchMesh load(const std::string& spec, bool triangulate, bool file_tags, sorpia::Tags& tags) {
  tags = sorpia::Tags{};
  if (!is_generated(spec)) {
    sorpia::MeshFile file = sorpia::read_mesh(spec, sorpia::ReadOptions{triangulate, file_tags});
    tags = std::move(file.tags.tags);
    return sorpia::Mesh(std::move(file));
  }
  try {
    return generate(spec);
  } catch (const sorpia::ParameterError& e) {  // e.g. icosphere:11: a bad argument
    throw Usage("mesh '" + spec + "': " + e.what());
  }
}

BenchMesh generate(const std::string& spec) {
  const std::string kind = spec.substr(0, spec.find(':'));
  if (kind == "icosphere") return sorpia::icosphere(spec_numbers(spec, 'x', 1, 1)[0]);
  if (kind == "pole") return sorpia::pole(spec_numbers(spec, 'x', 1, 1)[0]);
  if (kind == "torus" || kind == "grid" || kind == "quadtorus" || kind == "quadgrid") {
    const auto n = spec_numbers(spec, 'x', 2, 2);
    if (kind == "quadtorus") return sorpia::quad_torus(n[0], n[1]);
    if (kind == "quadgrid") return sorpia::quad_grid(n[0], n[1]);
    return kind == "torus" ? sorpia::torus(n[0], n[1]) : sorpia::grid(n[0], n[1]);
  }
  if (kind == "irregular" || kind == "quads") {
    const auto n = spec_numbers(spec, ':', 1, 2);
    const auto seed = n.size() > 1 ? static_cast<std::uint32_t>(n[1]) : 1u;
    if (kind == "quads") return sorpia::quad_irregular(n[0], seed);
    return sorpia::irregular(n[0], seed);
  }
  if (kind == "polygons") {
    const auto parts = split(spec.substr(spec.find(':') + 1), ':');
    const auto n = spec_numbers(kind + ":" + parts[0], 'x', 2, 2);
    const auto seed = parts.size() > 1 ? static_cast<std::uint32_t>(to_int(spec, parts[1], 0)) : 1u;
    return sorpia::polygon_torus(n[0], n[1], seed);
  }
  throw Usage("unknown generated mesh '" + kind +
              "' (icosphere, torus, irregular, grid, pole, quadtorus, quadgrid, quads, polygons)");
}

// Each edge of the mesh, with probability `share` (a fixed draw), appended to
// `tags` as a crease of the given sharpness.
void add_random_creases(const sorpia::Topology& topology, double share, double sharpness, sorpia::Tags& tags) {
  if (share <= 0.0) return;
  std::mt19937_64 rng(1);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  const auto& offsets = topology.ring_offsets();
  const auto& ring = topology.ring_neighbors();
  for (std::size_t v = 0; v < topology.n_vertices(); ++v)
    for (std::int32_t p = offsets[v]; p < offsets[v + 1]; ++p)
      if (static_cast<std::size_t>(ring[p]) > v && u(rng) < share) {
        tags.crease_vertices.push_back(static_cast<std::int32_t>(v));
        tags.crease_vertices.push_back(ring[p]);
        tags.crease_sharpness.push_back(sharpness);
      }
}

std::string label_of(const std::string& spec) {
  if (is_generated(spec)) return spec;
  const auto slash = spec.find_last_of('/');
  return slash == std::string::npos ? spec : spec.substr(slash + 1);
}

// ---- measurement ---------------------------------------------------------------

using Clock = std::chrono::steady_clock;
double seconds_since(Clock::time_point t0) { return std::chrono::duration<double>(Clock::now() - t0).count(); }

// kB from /proc/self/status ("VmRSS", "VmHWM"); 0 where unavailable.
long status_kb(const char* key) {
  std::ifstream in("/proc/self/status");
  for (std::string line; std::getline(in, line);)
    if (line.rfind(key, 0) == 0) return std::atol(line.c_str() + std::string(key).size() + 1);
  return 0;
}

// Hands freed heap back to the system (glibc keeps it otherwise, and the
// resident size would count what earlier meshes freed), then resets VmHWM to
// the current resident size (Linux >= 4.0), so that each mesh gets its own peak.
void reset_peak() {
#ifdef __GLIBC__
  malloc_trim(0);
#endif
  std::ofstream("/proc/self/clear_refs") << "5";
}

double median(std::vector<double> x) {
  if (x.empty()) return NAN;
  std::sort(x.begin(), x.end());
  const std::size_t m = x.size() / 2;
  return x.size() % 2 ? x[m] : 0.5 * (x[m - 1] + x[m]);
}

// The streaming floor: the memory traffic of one sweep at full bandwidth. It
// reads every array a sweep reads (the operator's offsets, neighbour indices,
// diagonal and weights, V0 as (n, 3) doubles in place) and reads and writes V
// as the engine holds it, (n, 4) doubles (32 bytes a vertex, the fourth lane
// padding), each once and in order, with no gather of neighbour positions and
// no per-row branching: the neighbour indices are summed as one flat array.
// The fastest of 7 passes: a floor, so the pass least disturbed by other
// processes.
double streaming_floor(const sorpia::LimitOperator& op, const double* v0) {
  std::vector<double> v(4 * op.n);
  for (std::size_t i = 0; i < op.n; ++i)
    for (int k = 0; k < 3; ++k) v[4 * i + k] = v0[3 * i + k];
  std::vector<double> times;
  volatile double sink = 0;
  const std::size_t nnz = op.neighbors.size();
  for (int r = 0; r < 7; ++r) {
    const auto t0 = Clock::now();
    std::int64_t idx = 0;
    for (std::size_t p = 0; p < nnz; ++p) idx += op.neighbors[p];
    for (std::size_t i = 0; i < op.n; ++i) {
      const double s = op.diag[i] + op.weight[i] + op.offsets[i];
      for (int k = 0; k < 3; ++k) v[4 * i + k] = 0.5 * v[4 * i + k] + 1e-30 * s * v0[3 * i + k];
      v[4 * i + 3] = 0.5 * v[4 * i + 3];
    }
    times.push_back(seconds_since(t0));
    sink = sink + v[0] + static_cast<double>(idx);
  }
  return *std::min_element(times.begin(), times.end());
}

struct MethodRun {
  std::string method;
  std::vector<double> solve, estimate, write;
  int iterations = 0;
  double final_error = NAN, omega = NAN;
  std::string stop;
  int threads = 1;
  bool reordered = false;
};

struct MeshRun {
  std::string label;
  std::size_t n_vertices = 0, n_faces = 0, n_creases = 0;
  std::vector<double> read, topology, op;
  std::vector<MethodRun> methods;
  double floor = NAN;
  long peak_kb = 0, input_kb = 0;
};

std::string output_path(const Options& o, const std::string& label, const std::string& method) {
  std::string name = label;
  for (char& c : name)
    if (c == ':' || c == '/' || c == ' ') c = '_';
  const std::string ext = o.format == "ply-ascii" ? "ply" : o.format;
  return o.write_dir + "/" + name + "." + method + "." + ext;
}

MeshRun run_mesh(const Options& o, const std::string& spec) {
  MeshRun run;
  run.label = label_of(spec);
  for (const auto& m : o.methods)
    if (m != "none") run.methods.push_back(MethodRun{m, {}, {}, {}, 0, NAN, NAN, ""});
  for (int rep = 0; rep < o.repeat; ++rep) {
    auto t0 = Clock::now();
    sorpia::Tags tags;
    const BenchMesh mesh = load(spec, o.triangulate, o.file_tags, tags);
    run.read.push_back(seconds_since(t0));
    run.n_vertices = mesh.n_vertices();
    run.n_faces = mesh.n_faces();
    reset_peak();
    const long input_kb = status_kb("VmRSS");

    t0 = Clock::now();
    sorpia::Topology topology(mesh.mesh);
    run.topology.push_back(seconds_since(t0));

    add_random_creases(topology, o.crease_share, o.crease_sharpness, tags);
    run.n_creases = tags.n_creases();
    sorpia::Rules rules{o.scheme, o.boundary, std::move(tags)};
    t0 = Clock::now();
    sorpia::Interpolator interp(std::move(topology), rules);
    run.op.push_back(seconds_since(t0));
    const sorpia::LimitOperator& op = interp.limit_operator();

    for (auto& mr : run.methods) {
      sorpia::SolveOptions so;
      so.method = sorpia::parse_method(mr.method);
      so.tol = o.tol;
      so.max_iter = o.max_iter;
      const bool sweeps = so.method == sorpia::Method::Sor || so.method == sorpia::Method::Gs;
      so.threads = sweeps ? o.threads : 1;
      so.two_pass = o.two_pass;
      if (so.method == sorpia::Method::Sor) {  // --omega is sor's; the other methods have none
        so.omega_rule = o.omega_rule;
        so.omega = o.omega;
      }
      // Each method pays for its own spectral estimates, as a single solve does.
      interp.spectral_cache() = sorpia::SpectralCache{};
      t0 = Clock::now();
      const sorpia::SolveResult res = interp.solve(mesh.vertices().data(), 3, nullptr, so, false);
      const double wall = seconds_since(t0);
      mr.solve.push_back(wall - res.estimate_seconds);
      mr.estimate.push_back(res.estimate_seconds);
      mr.iterations = res.iterations;
      mr.final_error = res.errors.empty() ? NAN : res.errors.back();
      mr.omega = res.omega;
      mr.stop = sorpia::stop_reason_name(res.stop_reason);
      mr.threads = so.threads;
      mr.reordered = res.reordered;
      if (!o.write_dir.empty()) {
        t0 = Clock::now();
        const sorpia::MeshView view{res.control_vertices.data(), mesh.n_vertices(),
                                    mesh.mesh.face_vertex_indices.data(), mesh.n_faces(),
                                    mesh.polygons() ? mesh.mesh.face_vertex_counts.data() : nullptr, 3};
        sorpia::write_mesh(output_path(o, run.label, mr.method), view, o.format == "ply");
        mr.write.push_back(seconds_since(t0));
      }
    }
    if (rep == 0) {
      run.peak_kb = status_kb("VmHWM");
      run.input_kb = input_kb;
      if (!run.methods.empty()) run.floor = streaming_floor(op, mesh.vertices().data());
    }
  }
  return run;
}

// ---- fair interpolation and approximation ------------------------------------------

// One mesh's run of a pipeline: seconds per phase over the repeats (medians reported, in this order) and facts
// of the last run (counts, iterations, stop reasons, figures), printed as they are.
struct PipelineRun {
  std::string label;
  std::vector<std::pair<std::string, std::vector<double>>> phases;
  std::vector<std::pair<std::string, std::string>> facts;
  long peak_kb = 0;

  void add(const std::string& phase, double seconds) {
    for (auto& [name, times] : phases)
      if (name == phase) {
        times.push_back(seconds);
        return;
      }
    phases.push_back({phase, {seconds}});
  }
  void fact(const std::string& name, const std::string& value) {
    for (auto& [n, v] : facts)
      if (n == name) {
        v = value;
        return;
      }
    facts.push_back({name, value});
  }
};

std::string num(double x);

// sorpia::fair_interpolate of every vertex: the Interpolator's build, then the pipeline's phases.
PipelineRun run_fair(const Options& o, const std::string& spec) {
  PipelineRun run;
  run.label = label_of(spec);
  for (int rep = 0; rep < o.repeat; ++rep) {
    sorpia::Tags tags;
    const BenchMesh mesh = load(spec, o.triangulate, o.file_tags, tags);
    reset_peak();
    const auto t0 = Clock::now();
    sorpia::Topology topology(mesh.mesh);
    add_random_creases(topology, o.crease_share, o.crease_sharpness, tags);
    sorpia::Interpolator interp(std::move(topology), sorpia::Rules{o.scheme, o.boundary, std::move(tags)});
    run.add("build", seconds_since(t0));
    sorpia::FairInterpolationOptions fo;
    fo.levels = o.levels;
    fo.membrane = o.membrane;
    fo.solve.tol = o.fair_tol;
    fo.solve.threads = o.threads;
    fo.plain.method = sorpia::parse_method(o.methods.front() == "none" ? "auto" : o.methods.front());
    fo.plain.tol = o.tol;
    fo.plain.max_iter = o.max_iter;
    const auto t1 = Clock::now();
    const sorpia::FairInterpolationResult r =
        sorpia::fair_interpolate(interp, mesh.vertices().data(), nullptr, 0, fo);
    const double total = seconds_since(t1);
    run.add("plain", r.plain_seconds);
    run.add("refine", r.refine_seconds);
    run.add("energy", r.energy_seconds);
    run.add("setup", r.solution.setup_seconds);
    run.add("solve", r.solution.seconds);
    run.add("total", seconds_since(t0));
    run.add("pipeline", total);
    run.fact("vertices", std::to_string(mesh.n_vertices()));
    run.fact("fine_vertices", std::to_string(r.fine.n_vertices));
    run.fact("plain_iterations", std::to_string(r.plain.iterations));
    run.fact("iterations", std::to_string(r.solution.iterations));
    run.fact("stop", r.solution.stop_reason);
    run.fact("energy_over_plain", num(r.solution.energy / r.solution.start_energy));
    run.fact("max_error", num(r.solution.max_error));
    if (rep == 0) run.peak_kb = status_kb("VmHWM");
  }
  return run;
}

// sorpia::approximate of the mesh's vertices by the mesh decimated (OpenMesh's Decimater; quads under
// Catmull-Clark): the cage's build, then the pipeline's phases.
PipelineRun run_approximate(const Options& o, const std::string& spec) {
  PipelineRun run;
  run.label = label_of(spec);
  for (int rep = 0; rep < o.repeat; ++rep) {
    sorpia::Tags tags;
    const BenchMesh mesh = load(spec, true, false, tags);
    reset_peak();
    const std::size_t n = mesh.n_vertices();
    const std::size_t wanted =
        o.cage_vertices > 0 ? static_cast<std::size_t>(o.cage_vertices) : std::max<std::size_t>(50, n / 50);
    auto t0 = Clock::now();
    sorpia::DecimateOptions d;
    d.scheme = o.scheme;
    std::string stopped;
    sorpia::Mesh cage = sorpia::decimate(mesh.mesh, wanted, d, &stopped);
    run.add("cage", seconds_since(t0));
    t0 = Clock::now();
    if (!cage.uniform() || cage.face_size != 3) cage.face_vertex_counts = cage.counts();
    const std::vector<double> cage_vertices = cage.vertices;
    const sorpia::Topology topology(cage);
    sorpia::LimitSurface surface(topology, cage_vertices.data(), o.scheme, o.boundary);
    run.add("surface", seconds_since(t0));
    sorpia::ApproximationOptions ao;
    ao.iterations = o.iterations;
    ao.fairness = o.fairness;
    ao.update = o.update;
    if (o.update == sorpia::ApproximationUpdate::LSPIA) ao.tangential = 1.0;
    const sorpia::ApproximationResult r = sorpia::approximate(surface, mesh.vertices().data(), n, nullptr, ao);
    run.add("footpoints", r.seconds.footpoints);
    run.add("rows", r.seconds.rows);
    run.add("normal", r.seconds.normal);
    run.add("solve", r.seconds.solve);
    run.add("report", r.seconds.report);
    run.add("pipeline", r.seconds.total);
    run.fact("points", std::to_string(n));
    run.fact("cage_vertices", std::to_string(cage_vertices.size() / 3));
    run.fact("iterations", std::to_string(r.iterations));
    run.fact("best_iteration", std::to_string(r.best_iteration));
    run.fact("stop", r.stop_reason);
    run.fact("rms_start", num(r.history.front().rms_relative));
    run.fact("rms", num(r.history[static_cast<std::size_t>(r.best_iteration)].rms_relative));
    run.fact("max", num(r.history[static_cast<std::size_t>(r.best_iteration)].max_relative));
    if (rep == 0) run.peak_kb = status_kb("VmHWM");
  }
  return run;
}

// ---- output --------------------------------------------------------------------

std::string json_str(const std::string& s) {
  std::string out = "\"";
  for (char c : s) {
    if (c == '"' || c == '\\') out += '\\';
    if (static_cast<unsigned char>(c) >= 0x20) out += c;
  }
  return out + "\"";
}

std::string num(double x) {
  if (!std::isfinite(x)) return "null";
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.6g", x);
  return buf;
}

std::string fixed3(double x) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.3f", x);
  return buf;
}

double bytes_per_vertex(const MeshRun& r) {
  return r.n_vertices ? 1024.0 * static_cast<double>(r.peak_kb - r.input_kb) / static_cast<double>(r.n_vertices) : NAN;
}

std::string cpu_model() {
  std::ifstream in("/proc/cpuinfo");
  for (std::string line; std::getline(in, line);)
    if (line.rfind("model name", 0) == 0) return line.substr(line.find(':') + 2);
  return "unknown";
}

void print_json(const Options& o, const std::vector<MeshRun>& runs) {
  std::printf("{\n  \"machine\": {\"cpu\": %s, \"hardware_threads\": %u},\n", json_str(cpu_model()).c_str(),
              std::thread::hardware_concurrency());
  std::printf("  \"options\": {\"tol\": %s, \"max_iter\": %d, \"scheme\": %s, \"boundary\": %s, "
              "\"threads\": %d, \"two_pass\": %s, \"repeat\": %d},\n",
              num(o.tol).c_str(), o.max_iter, json_str(sorpia::scheme_name(o.scheme)).c_str(),
              json_str(sorpia::boundary_name(o.boundary)).c_str(), o.threads,
              o.two_pass ? "true" : "false", o.repeat);
  std::printf("  \"meshes\": [");
  for (std::size_t k = 0; k < runs.size(); ++k) {
    const MeshRun& r = runs[k];
    std::printf("%s\n    {\"mesh\": %s, \"n_vertices\": %zu, \"n_faces\": %zu, \"n_creases\": %zu, \"read\": %s, \"topology\": %s, "
                "\"operator\": %s, \"floor\": %s, \"peak_rss_bytes\": %ld, \"input_rss_bytes\": %ld, "
                "\"bytes_per_vertex\": %s, \"methods\": [",
                k ? "," : "", json_str(r.label).c_str(), r.n_vertices, r.n_faces, r.n_creases, num(median(r.read)).c_str(),
                num(median(r.topology)).c_str(), num(median(r.op)).c_str(), num(r.floor).c_str(), 1024 * r.peak_kb,
                1024 * r.input_kb, num(bytes_per_vertex(r)).c_str());
    for (std::size_t j = 0; j < r.methods.size(); ++j) {
      const MethodRun& m = r.methods[j];
      const double solve = median(m.solve);
      const double sweep = m.iterations ? solve / m.iterations : NAN;
      std::printf("%s\n      {\"method\": %s, \"solve\": %s, \"estimate\": %s, \"write\": %s, \"iterations\": %d, "
                  "\"final_error\": %s, \"stop\": %s, \"omega\": %s, \"threads\": %d, \"reordered\": %s, "
                  "\"sweep\": %s, \"sweep_over_floor\": %s, \"end_to_end\": %s}",
                  j ? "," : "", json_str(m.method).c_str(), num(solve).c_str(), num(median(m.estimate)).c_str(),
                  num(median(m.write)).c_str(), m.iterations, num(m.final_error).c_str(), json_str(m.stop).c_str(),
                  num(m.omega).c_str(), m.threads, m.reordered ? "true" : "false", num(sweep).c_str(), num(sweep / r.floor).c_str(),
                  num(median(r.topology) + median(r.op) + solve + median(m.estimate)).c_str());
    }
    std::printf("]}");
  }
  std::printf("\n  ]\n}\n");
}

void print_table(const Options& o, const std::vector<MeshRun>& runs) {
  std::printf("sorpia-bench: %s, %u hardware threads; sor/gs on %d thread%s%s; tol %g; %s; %s; "
              "medians of %d\n",
              cpu_model().c_str(), std::thread::hardware_concurrency(), o.threads, o.threads > 1 ? "s" : "",
              o.two_pass ? " (two-pass E_k)" : "", o.tol, sorpia::scheme_name(o.scheme), sorpia::boundary_name(o.boundary),
              o.repeat);
  std::printf("%-22s %9s %7s %8s %8s %-6s %7s %8s %6s %9s %8s %9s %8s %8s\n", "mesh", "vertices", "read", "topology",
              "operator", "method", "solve", "estimate", "iters", "E_k/E_0", "write", "sweep/fl", "peak MB",
              "B/vertex");
  // a method that stopped for another reason than convergence is marked
  // with its reason after the error
  for (const MeshRun& r : runs) {
    const std::size_t rows = std::max<std::size_t>(1, r.methods.size());
    for (std::size_t j = 0; j < rows; ++j) {
      const bool first = j == 0;
      if (first)
        std::printf("%-22s %9zu %7.3f %8.3f %8.3f ", r.label.c_str(), r.n_vertices, median(r.read),
                    median(r.topology), median(r.op));
      else
        std::printf("%-22s %9s %7s %8s %8s ", "", "", "", "", "");
      if (r.methods.empty()) {
        std::printf("%-6s %7s %8s %6s %9s %8s %9s ", "none", "-", "-", "-", "-", "-", "-");
      } else {
        const MethodRun& m = r.methods[j];
        const double solve = median(m.solve);
        const std::string stop = m.stop == "converged" ? "" : "(" + m.stop + ")";
        const std::string write = m.write.empty() ? "-" : fixed3(median(m.write));
        std::printf("%-6s %7.3f %8.3f %6d %9.2e%s %8s %9.2f ", m.method.c_str(), solve, median(m.estimate),
                    m.iterations, m.final_error, stop.c_str(), write.c_str(),
                    m.iterations ? solve / m.iterations / r.floor : NAN);
      }
      if (first)
        std::printf("%8.1f %8.0f\n", r.peak_kb / 1024.0, bytes_per_vertex(r));
      else
        std::printf("\n");
    }
  }
  const bool any_floor = std::any_of(runs.begin(), runs.end(), [](const MeshRun& r) { return !r.methods.empty(); });
  if (any_floor) {
    std::printf("floor (s):");
    for (const MeshRun& r : runs) std::printf(" %s %.4f", r.label.c_str(), r.floor);
    std::printf("\n");
  }
}

const char* task_name(Task t) {
  return t == Task::Fair ? "fair" : t == Task::Approximate ? "approximate" : "interpolate";
}

void print_pipeline_json(const Options& o, const std::vector<PipelineRun>& runs) {
  std::printf("{\n  \"machine\": {\"cpu\": %s, \"hardware_threads\": %u},\n", json_str(cpu_model()).c_str(),
              std::thread::hardware_concurrency());
  std::printf("  \"task\": %s,\n  \"options\": {\"scheme\": %s, \"boundary\": %s, \"threads\": %d, \"repeat\": %d},\n",
              json_str(task_name(o.task)).c_str(), json_str(sorpia::scheme_name(o.scheme)).c_str(),
              json_str(sorpia::boundary_name(o.boundary)).c_str(), o.threads, o.repeat);
  std::printf("  \"meshes\": [");
  for (std::size_t k = 0; k < runs.size(); ++k) {
    const PipelineRun& r = runs[k];
    std::printf("%s\n    {\"mesh\": %s, \"peak_rss_bytes\": %ld", k ? "," : "", json_str(r.label).c_str(),
                1024 * r.peak_kb);
    for (const auto& [name, times] : r.phases) std::printf(", %s: %s", json_str(name).c_str(), num(median(times)).c_str());
    for (const auto& [name, value] : r.facts) std::printf(", %s: %s", json_str(name).c_str(), json_str(value).c_str());
    std::printf("}");
  }
  std::printf("\n  ]\n}\n");
}

void print_pipeline_table(const Options& o, const std::vector<PipelineRun>& runs) {
  std::printf("sorpia-bench --task %s: %s, %u hardware threads; %s; %s; seconds, medians of %d\n", task_name(o.task),
              cpu_model().c_str(), std::thread::hardware_concurrency(), sorpia::scheme_name(o.scheme),
              sorpia::boundary_name(o.boundary), o.repeat);
  for (const PipelineRun& r : runs) {
    std::printf("%s:", r.label.c_str());
    for (const auto& [name, times] : r.phases) std::printf(" %s %.3f", name.c_str(), median(times));
    std::printf("; peak %.1f MB\n ", r.peak_kb / 1024.0);
    for (const auto& [name, value] : r.facts) std::printf(" %s %s", name.c_str(), value.c_str());
    std::printf("\n");
  }
}

}  // namespace

int main(int argc, char** argv) {
  Options o;
  try {
    o = parse(argc, argv);
  } catch (const Usage& e) {
    std::fprintf(stderr, "sorpia-bench: %s\n\n%s", e.what(), kUsage);
    return 2;
  }
  std::vector<MeshRun> runs;
  std::vector<PipelineRun> pipelines;
  try {
    for (const auto& spec : o.meshes) {
      if (o.task == Task::Fair)
        pipelines.push_back(run_fair(o, spec));
      else if (o.task == Task::Approximate)
        pipelines.push_back(run_approximate(o, spec));
      else
        runs.push_back(run_mesh(o, spec));
    }
  } catch (const Usage& e) {
    std::fprintf(stderr, "sorpia-bench: %s\n\n%s", e.what(), kUsage);
    return 2;
  } catch (const std::exception& e) {  // MeshError, FileError, ParameterError, bad_alloc
    std::fprintf(stderr, "sorpia-bench: %s\n", e.what());
    return 1;
  }
  if (o.task != Task::Interpolate)
    (o.json ? print_pipeline_json : print_pipeline_table)(o, pipelines);
  else if (o.json)
    print_json(o, runs);
  else
    print_table(o, runs);
  return 0;
}
