#include "parallel/MpiAnalyses.h"

#include <mpi.h>

#include <chrono>
#include <csignal>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <iostream>
#include <list>
#include <map>
#include <set>
#include <stdexcept>
#include <thread>
#include <unordered_map>
#include <unordered_set>

#include "output/Checkpoint.h"
#include "scenarios/Plugins.h"

namespace crumble::mpi {

using Json = nlohmann::json;

namespace {

// Message tags. Rank 0 → workers: setup, job, stop; workers → rank 0: setup reply, result.
enum Tag : int { kSetup = 1, kJob = 2, kStop = 3, kSetupReply = 4, kResult = 5 };

// Jobs in flight per worker: the next one is there when the current one ends.
constexpr int kDepth = 2;
// Shapes a worker keeps (by rank 0's shape id); past this both sides forget them all.
constexpr std::size_t kShapeCacheLimit = 4096;

// ---------------------------------------------------------------- binary messages
// Plain bytes in this machine's representation: every rank of a run is the same binary on
// the same kind of machine, and doubles travel bit for bit.

struct Writer {
  std::vector<char> b;
  template <class T>
  void put(const T& v) {
    static_assert(std::is_trivially_copyable_v<T>);
    const char* p = reinterpret_cast<const char*>(&v);
    b.insert(b.end(), p, p + sizeof(T));
  }
  void size(std::size_t n) { put<std::uint64_t>(n); }
  void str(const std::string& s) {
    size(s.size());
    b.insert(b.end(), s.begin(), s.end());
  }
  void vec(const Vec3& v) {
    put(v.x);
    put(v.y);
    put(v.z);
  }
  void quat(const Quat& q) {
    put(q.w);
    put(q.x);
    put(q.y);
    put(q.z);
  }
  void bytes(const std::vector<std::uint8_t>& v) {
    size(v.size());
    b.insert(b.end(), v.begin(), v.end());
  }
};

struct Reader {
  const char* p;
  const char* end;
  explicit Reader(const std::vector<char>& b) : p(b.data()), end(b.data() + b.size()) {}
  void need(std::size_t n) const {
    if (static_cast<std::size_t>(end - p) < n) throw std::runtime_error("MPI message cut short");
  }
  template <class T>
  T get() {
    need(sizeof(T));
    T v;
    std::memcpy(&v, p, sizeof(T));
    p += sizeof(T);
    return v;
  }
  std::size_t size() {
    const auto n = get<std::uint64_t>();
    // Every element takes at least one byte.
    if (n > static_cast<std::uint64_t>(end - p)) throw std::runtime_error("MPI message: bad length");
    return static_cast<std::size_t>(n);
  }
  std::string str() {
    const std::size_t n = size();
    need(n);
    std::string s(p, p + n);
    p += n;
    return s;
  }
  Vec3 vec() {
    Vec3 v;
    v.x = get<double>();
    v.y = get<double>();
    v.z = get<double>();
    return v;
  }
  Quat quat() {
    Quat q;
    q.w = get<double>();
    q.x = get<double>();
    q.y = get<double>();
    q.z = get<double>();
    return q;
  }
  std::vector<std::uint8_t> bytes() {
    const std::size_t n = size();
    need(n);
    std::vector<std::uint8_t> v(p, p + n);
    p += n;
    return v;
  }
};

void put_grain(Writer& w, const Grain& g) {
  w.put<std::int64_t>(g.id);
  w.put<std::int64_t>(g.parent);
  w.put<std::int64_t>(g.origin);
  w.put<std::int32_t>(g.generation);
  w.put<std::int32_t>(g.material);
  w.put<std::int32_t>(g.crush_count);
  w.vec(g.position);
  w.quat(g.orientation);
  w.vec(g.velocity);
  w.vec(g.angular_velocity);
  w.size(g.strength.values.size());
  for (const auto& [k, v] : g.strength.values) {
    w.str(k);
    w.put(v);
  }
}

Grain get_grain(Reader& r) {
  Grain g;
  g.id = r.get<std::int64_t>();
  g.parent = r.get<std::int64_t>();
  g.origin = r.get<std::int64_t>();
  g.generation = r.get<std::int32_t>();
  g.material = r.get<std::int32_t>();
  g.crush_count = r.get<std::int32_t>();
  g.position = r.vec();
  g.orientation = r.quat();
  g.velocity = r.vec();
  g.angular_velocity = r.vec();
  const std::size_t n = r.size();
  for (std::size_t i = 0; i < n; ++i) {
    std::string k = r.str();
    g.strength.values[k] = r.get<double>();
  }
  return g;
}

void put_contact(Writer& w, const Contact& c) {
  w.put<std::int64_t>(c.a);
  w.put<std::int64_t>(c.b);
  w.put<std::int32_t>(c.wall);
  w.vec(c.point);
  w.vec(c.normal);
  w.vec(c.force);
  w.vec(c.torque);
  w.put(c.overlap);
}

Contact get_contact(Reader& r) {
  Contact c;
  c.a = r.get<std::int64_t>();
  c.b = r.get<std::int64_t>();
  c.wall = r.get<std::int32_t>();
  c.point = r.vec();
  c.normal = r.vec();
  c.force = r.vec();
  c.torque = r.vec();
  c.overlap = r.get<double>();
  return c;
}

void put_vecs(Writer& w, const std::vector<Vec3>& v) {
  w.size(v.size());
  for (const auto& x : v) w.vec(x);
}
std::vector<Vec3> get_vecs(Reader& r) {
  std::vector<Vec3> v(r.size());
  for (auto& x : v) x = r.vec();
  return v;
}

void put_analysis(Writer& w, const BreakageAnalysis& a) {
  w.put<std::uint8_t>(a.broken);
  w.str(a.outcome);
  w.put(a.load);
  w.put(a.wall_ms);
  w.size(a.figures.size());
  for (const auto& [k, v] : a.figures) {
    w.str(k);
    w.put(v);
  }
  if (!a.fracture) {
    w.put<std::uint8_t>(0);
  } else if (const auto* pc = std::get_if<PointClusters>(&*a.fracture)) {
    w.put<std::uint8_t>(1);
    w.put(pc->spacing);
    put_vecs(w, pc->points);
    w.size(pc->cluster.size());
    for (int c : pc->cluster) w.put<std::int32_t>(c);
    w.size(pc->on_surface.size());
    for (char c : pc->on_surface) w.put(c);
    w.put<std::int32_t>(pc->clusters);
    w.size(pc->fracture_points.size());
    for (const auto& f : pc->fracture_points) put_vecs(w, f);
    w.quat(pc->frame);
  } else {
    const auto& cs = std::get<CuttingSurfaces>(*a.fracture);
    w.put<std::uint8_t>(2);
    w.size(cs.planes.size());
    for (const auto& p : cs.planes) {
      w.vec(p.normal);
      w.put(p.offset);
    }
  }
  w.put<std::uint8_t>(a.points != nullptr);
  if (a.points) {
    put_vecs(w, a.points->points);
    w.size(a.points->scalars.size());
    for (const auto& [name, v] : a.points->scalars) {
      w.str(name);
      w.size(v.size());
      for (double x : v) w.put(x);
    }
    w.size(a.points->vectors.size());
    for (const auto& [name, v] : a.points->vectors) {
      w.str(name);
      put_vecs(w, v);
    }
  }
}

BreakageAnalysis get_analysis(Reader& r) {
  BreakageAnalysis a;
  a.broken = r.get<std::uint8_t>() != 0;
  a.outcome = r.str();
  a.load = r.get<double>();
  a.wall_ms = r.get<double>();
  const std::size_t nf = r.size();
  for (std::size_t i = 0; i < nf; ++i) {
    std::string k = r.str();
    a.figures.emplace_back(std::move(k), r.get<double>());
  }
  const auto kind = r.get<std::uint8_t>();
  if (kind == 1) {
    PointClusters pc;
    pc.spacing = r.get<double>();
    pc.points = get_vecs(r);
    pc.cluster.resize(r.size());
    for (int& c : pc.cluster) c = r.get<std::int32_t>();
    pc.on_surface.resize(r.size());
    for (char& c : pc.on_surface) c = r.get<char>();
    pc.clusters = r.get<std::int32_t>();
    pc.fracture_points.resize(r.size());
    for (auto& f : pc.fracture_points) f = get_vecs(r);
    pc.frame = r.quat();
    a.fracture = std::move(pc);
  } else if (kind == 2) {
    CuttingSurfaces cs;
    cs.planes.resize(r.size());
    for (auto& p : cs.planes) {
      p.normal = r.vec();
      p.offset = r.get<double>();
    }
    a.fracture = std::move(cs);
  } else if (kind != 0) {
    throw std::runtime_error("MPI message: unknown fracture kind");
  }
  if (r.get<std::uint8_t>()) {
    auto pts = std::make_shared<AnalysisPointCloud>();
    pts->points = get_vecs(r);
    pts->scalars.resize(r.size());
    for (auto& [name, v] : pts->scalars) {
      name = r.str();
      v.resize(r.size());
      for (double& x : v) x = r.get<double>();
    }
    pts->vectors.resize(r.size());
    for (auto& [name, v] : pts->vectors) {
      name = r.str();
      v = get_vecs(r);
    }
    a.points = std::move(pts);
  }
  return a;
}

// ---------------------------------------------------------------- point-to-point

void send(const Writer& w, int to, int tag) {
  MPI_Send(w.b.data(), static_cast<int>(w.b.size()), MPI_BYTE, to, tag, MPI_COMM_WORLD);
}

// A message already probed: receive its bytes.
std::vector<char> receive(const MPI_Status& st) {
  int n = 0;
  MPI_Get_count(&st, MPI_BYTE, &n);
  std::vector<char> b(static_cast<std::size_t>(n));
  MPI_Recv(b.data(), n, MPI_BYTE, st.MPI_SOURCE, st.MPI_TAG, MPI_COMM_WORLD, MPI_STATUS_IGNORE);
  return b;
}

// Sends that may wait for their receiver (rendezvous for large messages) without blocking
// the sender: each keeps its buffer until it completes.
class PendingSends {
 public:
  void add(std::vector<char> b, int to, int tag) {
    items_.emplace_back(std::move(b), MPI_REQUEST_NULL);
    auto& [buf, req] = items_.back();
    MPI_Isend(buf.data(), static_cast<int>(buf.size()), MPI_BYTE, to, tag, MPI_COMM_WORLD, &req);
  }
  void test() {
    for (auto it = items_.begin(); it != items_.end();) {
      int done = 0;
      MPI_Test(&it->second, &done, MPI_STATUS_IGNORE);
      it = done ? items_.erase(it) : std::next(it);
    }
  }
  void wait_all() {
    for (auto& [buf, req] : items_) MPI_Wait(&req, MPI_STATUS_IGNORE);
    items_.clear();
  }

 private:
  std::list<std::pair<std::vector<char>, MPI_Request>> items_;
};

// Waiting without spinning: a rank that waits for work (the workers while rank 0 steps the
// engine) must leave its core to the engine (Open MPI's blocking receive polls at 100 %).
class Backoff {
 public:
  void reset() { us_ = 20; }
  void wait() {
    std::this_thread::sleep_for(std::chrono::microseconds(us_));
    us_ = std::min(us_ * 2, 2000);
  }

 private:
  int us_ = 20;
};

bool probe(int source, int tag, MPI_Status* st) {
  int flag = 0;
  MPI_Iprobe(source, tag, MPI_COMM_WORLD, &flag, st);
  return flag != 0;
}

// ---------------------------------------------------------------- rank 0

class MpiExecutor : public AnalysisExecutor {
 public:
  explicit MpiExecutor(int size) : size_(size), outstanding_(size, 0), sent_(size), load_(size) {}
  ~MpiExecutor() override {
    // An analyse() left by an exception: collect what is still on its way, so that every
    // worker is idle (waiting for stop) and no send is left open.
    Backoff b;
    while (in_flight() > 0) {
      MPI_Status st;
      if (probe(MPI_ANY_SOURCE, kResult, &st)) {
        receive(st);
        --outstanding_[st.MPI_SOURCE];
      } else {
        b.wait();
      }
    }
    sends_.wait_all();
  }

  int ranks() const override { return size_; }
  std::vector<RankLoad> load() const override { return load_; }

  void analyse(const BreakageModel& model, const std::vector<Material>& materials, std::span<const AnalysisJob> jobs,
               std::vector<BreakageAnalysis>& results, std::vector<std::string>& errors) override {
    const std::size_t n = jobs.size();
    std::size_t next = 0, done = 0;
    auto dispatch = [&](int w) {
      Writer m;
      const std::size_t k = next++;
      const Grain& g = *jobs[k].grain;
      std::uint8_t flags = 0;
      if (sent_[w].size() >= kShapeCacheLimit) {
        sent_[w].clear();
        flags |= 1;  // forget every shape
      }
      const std::uint64_t sid = shape_id(g.shape);
      const bool with_shape = sent_[w].insert(sid).second;
      if (with_shape) flags |= 2;
      m.put(flags);
      m.put<std::uint64_t>(k);
      m.put(sid);
      if (with_shape) m.bytes(Json::to_cbor(shape_saved_json(*g.shape)));
      put_grain(m, g);
      m.put<std::int32_t>(jobs[k].material);
      m.size(jobs[k].contacts.size());
      for (const auto& c : jobs[k].contacts) put_contact(m, c);
      sends_.add(std::move(m.b), w, kJob);
      ++outstanding_[w];
    };
    for (int d = 0; d < kDepth; ++d)
      for (int w = 1; w < size_ && next < n; ++w) dispatch(w);
    Backoff b;
    while (done < n) {
      MPI_Status st;
      if (probe(MPI_ANY_SOURCE, kResult, &st)) {
        b.reset();
        const std::vector<char> buf = receive(st);
        --outstanding_[st.MPI_SOURCE];
        Reader r(buf);
        const auto k = static_cast<std::size_t>(r.get<std::uint64_t>());
        if (k >= n) throw std::runtime_error("MPI: a worker answered a job that was not sent");
        if (r.get<std::uint8_t>()) {
          results[k] = get_analysis(r);
          ++load_[st.MPI_SOURCE].analyses;
          load_[st.MPI_SOURCE].seconds += results[k].wall_ms * 1e-3;
        } else errors[k] = r.str() + " (on MPI rank " + std::to_string(st.MPI_SOURCE) + ")";
        ++done;
        if (next < n) dispatch(st.MPI_SOURCE);
        sends_.test();
        continue;
      }
      if (next < n) {
        // Rank 0 works too: one job at a time, between the workers' replies.
        const std::size_t k = next++;
        const Grain& g = *jobs[k].grain;
        try {
          results[k] = model.analyse(g, materials.at(static_cast<std::size_t>(jobs[k].material)), jobs[k].contacts);
          ++load_[0].analyses;
          load_[0].seconds += results[k].wall_ms * 1e-3;
        } catch (const std::exception& e) {
          errors[k] = e.what();
        }
        ++done;
        continue;
      }
      b.wait();
    }
    sends_.wait_all();
  }

 private:
  int in_flight() const {
    int k = 0;
    for (int o : outstanding_) k += o;
    return k;
  }
  // One id per live shape: a shape that died and whose address was reused gets a new one.
  std::uint64_t shape_id(const Shape::Ptr& s) {
    auto it = ids_.find(s.get());
    if (it != ids_.end() && !it->second.first.expired()) return it->second.second;
    const std::uint64_t id = next_shape_++;
    ids_[s.get()] = {s, id};
    return id;
  }

  int size_;
  std::vector<int> outstanding_;
  std::vector<std::unordered_set<std::uint64_t>> sent_;  // per worker: shapes it holds
  std::unordered_map<const Shape*, std::pair<std::weak_ptr<const Shape>, std::uint64_t>> ids_;
  std::uint64_t next_shape_ = 0;
  PendingSends sends_;
  std::vector<RankLoad> load_;
};

// ---------------------------------------------------------------- workers

struct WorkerState {
  std::unique_ptr<Scenario> scenario;  // the run's model and materials
  std::unordered_map<std::uint64_t, Shape::Ptr> shapes;
  std::set<std::string> plugins;
};

void setup(WorkerState& ws, const std::vector<char>& buf, PendingSends& sends) {
  Writer reply;
  try {
    const Json msg = Json::from_cbor(buf.begin(), buf.end());
    for (const auto& p : msg.at("plugins"))
      if (ws.plugins.insert(p.get<std::string>()).second) load_plugin(p.get<std::string>());
    BuildOptions opt;
    opt.source_name = msg.at("source").get<std::string>();
    ws.scenario = std::make_unique<Scenario>(build_scenario(msg.at("document"), opt));
    ws.shapes.clear();
    reply.put<std::uint8_t>(1);
  } catch (const std::exception& e) {
    reply.put<std::uint8_t>(0);
    reply.str(e.what());
  }
  sends.add(std::move(reply.b), 0, kSetupReply);
}

std::vector<char> run_job(WorkerState& ws, const std::vector<char>& buf) {
  Writer out;
  Reader r(buf);
  const auto flags = r.get<std::uint8_t>();
  const auto k = r.get<std::uint64_t>();
  out.put(k);
  try {
    if (!ws.scenario) throw std::runtime_error("MPI worker: a job came before the scenario");
    const Simulation& sim = *ws.scenario->sim;
    if (flags & 1) ws.shapes.clear();
    const auto sid = r.get<std::uint64_t>();
    if (flags & 2) {
      const auto bytes = r.bytes();
      Json j = Json::from_cbor(bytes);
      ws.shapes[sid] = shape_from_saved_config(Config(j), sim.context().dimension);
    }
    Grain g = get_grain(r);
    auto it = ws.shapes.find(sid);
    if (it == ws.shapes.end()) throw std::runtime_error("MPI worker: job for a shape it was never sent");
    g.shape = it->second;
    const auto mat = r.get<std::int32_t>();
    std::vector<Contact> contacts(r.size());
    for (auto& c : contacts) c = get_contact(r);
    const BreakageAnalysis a =
        sim.model().analyse(g, sim.context().materials.at(static_cast<std::size_t>(mat)), contacts);
    out.put<std::uint8_t>(1);
    put_analysis(out, a);
  } catch (const std::exception& e) {
    out.b.resize(sizeof(std::uint64_t));
    out.put<std::uint8_t>(0);
    out.str(e.what());
  }
  return std::move(out.b);
}

bool launched_by_mpi() {
  for (const char* v : {"OMPI_COMM_WORLD_SIZE", "PMIX_RANK", "PMI_RANK", "PMI_SIZE"})
    if (std::getenv(v)) return true;
  return false;
}

}  // namespace

Session::Session(int* argc, char*** argv) {
  if (!launched_by_mpi()) return;
  int provided = 0;
  // Only the main thread calls MPI; OpenMP threads run the engine and fragment building.
  MPI_Init_thread(argc, argv, MPI_THREAD_FUNNELED, &provided);
  active_ = true;
  MPI_Comm_rank(MPI_COMM_WORLD, &rank_);
  MPI_Comm_size(MPI_COMM_WORLD, &size_);
}

Session::~Session() {
  if (!active_) return;
  if (rank_ == 0)
    for (int w = 1; w < size_; ++w) MPI_Send(nullptr, 0, MPI_BYTE, w, kStop, MPI_COMM_WORLD);
  MPI_Finalize();
}

int Session::serve() {
  // Ctrl-C reaches every rank: rank 0 finishes the step, writes its outputs and stops us.
  std::signal(SIGINT, SIG_IGN);
  std::signal(SIGTERM, SIG_IGN);
  WorkerState ws;
  PendingSends sends;
  Backoff b;
  for (;;) {
    MPI_Status st;
    if (!probe(0, MPI_ANY_TAG, &st)) {
      sends.test();
      b.wait();
      continue;
    }
    b.reset();
    const std::vector<char> buf = receive(st);
    if (st.MPI_TAG == kStop) break;
    if (st.MPI_TAG == kSetup) setup(ws, buf, sends);
    else if (st.MPI_TAG == kJob) sends.add(run_job(ws, buf), 0, kResult);
    sends.test();
  }
  sends.wait_all();
  return 0;
}

std::shared_ptr<AnalysisExecutor> Session::executor(const Json& document, const Scenario& sc,
                                                    const std::vector<std::string>& plugins) {
  if (!active_ || size_ < 2 || rank_ != 0) return nullptr;
  Json msg = {{"document", document}, {"source", sc.name}, {"plugins", plugins}};
  const std::vector<std::uint8_t> bytes = Json::to_cbor(msg);
  Writer w;
  w.b.assign(bytes.begin(), bytes.end());
  for (int r = 1; r < size_; ++r) send(w, r, kSetup);
  std::string failed;
  for (int r = 1; r < size_; ++r) {
    MPI_Status st;
    MPI_Probe(r, kSetupReply, MPI_COMM_WORLD, &st);
    const std::vector<char> buf = receive(st);
    Reader rd(buf);
    if (!rd.get<std::uint8_t>() && failed.empty()) failed = "MPI rank " + std::to_string(r) + ": " + rd.str();
  }
  if (!failed.empty()) throw std::runtime_error("the breakage model could not be built on every rank: " + failed);
  return std::make_shared<MpiExecutor>(size_);
}

std::string Session::describe() const {
  if (!active_) return {};
  char v[MPI_MAX_LIBRARY_VERSION_STRING];
  int len = 0;
  MPI_Get_library_version(v, &len);
  std::string s(v, static_cast<std::size_t>(len));
  if (auto p = s.find(','); p != std::string::npos) s.resize(p);
  return s + ", " + std::to_string(size_) + " ranks";
}

}  // namespace crumble::mpi
