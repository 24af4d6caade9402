#include "laser_output.h"

#include <fcntl.h>
#include <csignal>
#include <hdf5.h>
#include <sys/file.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <nlohmann/json.hpp>
#include <sstream>

namespace laser {

namespace fs = std::filesystem;

namespace {

const char* kLockName = ".laser_drill.lock";
const char* kPartSuffix = ".part";

// ------------------------------------------------------------------ HDF5
// Owns one HDF5 identifier; close() reports the status, the destructor closes
// quietly (an exception is already on its way).
class H5Id {
 public:
  using Closer = herr_t (*)(hid_t);
  H5Id() = default;
  H5Id(hid_t id, Closer c) : id_(id), close_(c) {}
  H5Id(H5Id&& o) noexcept : id_(o.id_), close_(o.close_) { o.id_ = -1; }
  H5Id& operator=(H5Id&& o) noexcept {
    if (this != &o) { reset(); id_ = o.id_; close_ = o.close_; o.id_ = -1; }
    return *this;
  }
  ~H5Id() { reset(); }
  hid_t get() const { return id_; }
  bool valid() const { return id_ >= 0; }
  bool close() {
    if (id_ < 0) return true;
    const herr_t s = close_(id_);
    id_ = -1;
    return s >= 0;
  }

 private:
  void reset() { if (id_ >= 0) close_(id_); id_ = -1; }
  hid_t id_ = -1;
  Closer close_ = nullptr;
};

// Streams frames into an HDF5 file: fixed node arrays first, then one row of
// every frame dataset per frame (chunked, unlimited in time), so memory stays
// at one frame whatever --frames is. Every dataset carries a "units" attribute.
class H5FrameWriter : public FrameSink {
 public:
  explicit H5FrameWriter(std::string path) : path_(std::move(path)) {
    H5Eset_auto2(H5E_DEFAULT, nullptr, nullptr);  // errors are reported by us, with the file name
    file_ = H5Id(H5Fcreate(path_.c_str(), H5F_ACC_TRUNC, H5P_DEFAULT, H5P_DEFAULT), H5Fclose);
    if (!file_.valid()) fail("cannot create the file");
  }
  ~H5FrameWriter() override = default;

  void begin(const std::vector<double>& xi, const std::vector<double>& t_melt) override {
    N_ = xi.size();
    write_fixed("xi", "1", xi);
    write_fixed("t_melt_s", "s", t_melt);
    for (const auto& s : series()) sets_.push_back(create_extendible(s.name, s.units, 0));
    for (const auto& f : fields()) sets_.push_back(create_extendible(f.name, f.units, N_));
  }

  void frame(const Frame& f) override {
    size_t k = 0;
    for (const auto& s : series()) append(sets_[k++], 0, &(f.*(s.member)));
    for (const auto& fl : fields()) {
      const std::vector<double>& v = f.*(fl.member);
      if (v.size() != N_) fail("frame of " + std::to_string(v.size()) + " nodes, expected " + std::to_string(N_));
      append(sets_[k++], N_, v.data());
    }
    ++rows_;
  }

  void finish() override {
    bool ok = true;
    for (auto& s : sets_) ok = s.close() && ok;
    sets_.clear();
    if (!ok) fail("closing a dataset failed");
    if (!file_.close()) fail("closing the file failed (disk full?)");
  }

 private:
  struct Series { const char* name; const char* units; double Frame::*member; };
  struct Field { const char* name; const char* units; std::vector<double> Frame::*member; };
  static const std::vector<Series>& series() {
    static const std::vector<Series> s = {
        {"time_s", "s", &Frame::t}, {"A", "1", &Frame::A}, {"u_peak_m_per_s", "m/s", &Frame::u_peak}};
    return s;
  }
  static const std::vector<Field>& fields() {
    static const std::vector<Field> f = {
        {"S1net_m", "m", &Frame::S1net},
        {"S2_m", "m", &Frame::S2},
        {"S1_vaporized_m", "m", &Frame::S1},
        {"g_m", "m", &Frame::g},
        {"theta_sat", "1", &Frame::theta_sat},
        {"T_surface_K", "K", &Frame::T},
        {"pressure_Pa", "Pa", &Frame::p},
        {"melting_rate_m_per_s", "m/s", &Frame::melt_rate},
        {"vaporization_rate_m_per_s", "m/s", &Frame::vap_rate},
        {"flow_v_m_per_s", "m/s", &Frame::flow_v},
        {"b2", "1", &Frame::b2}};
    return f;
  }
  [[noreturn]] void fail(const std::string& what) const {
    throw WriteError("cannot write " + path_ + ": HDF5: " + what);
  }
  void units(hid_t set, const char* u, const std::string& name) {
    H5Id type(H5Tcopy(H5T_C_S1), H5Tclose);
    if (!type.valid() || H5Tset_size(type.get(), std::strlen(u) + 1) < 0) fail("units type of " + name);
    H5Id space(H5Screate(H5S_SCALAR), H5Sclose);
    H5Id attr(H5Acreate2(set, "units", type.get(), space.get(), H5P_DEFAULT, H5P_DEFAULT), H5Aclose);
    if (!attr.valid() || H5Awrite(attr.get(), type.get(), u) < 0) fail("units attribute of " + name);
    if (!attr.close()) fail("units attribute of " + name);
  }
  void write_fixed(const std::string& name, const char* u, const std::vector<double>& data) {
    hsize_t dims[1] = {data.size()};
    H5Id space(H5Screate_simple(1, dims, nullptr), H5Sclose);
    H5Id set(H5Dcreate2(file_.get(), name.c_str(), H5T_IEEE_F64LE, space.get(), H5P_DEFAULT, H5P_DEFAULT,
                        H5P_DEFAULT), H5Dclose);
    if (!set.valid()) fail("cannot create dataset /" + name);
    if (!data.empty() && H5Dwrite(set.get(), H5T_NATIVE_DOUBLE, H5S_ALL, H5S_ALL, H5P_DEFAULT, data.data()) < 0)
      fail("cannot write dataset /" + name);
    units(set.get(), u, name);
    if (!set.close()) fail("closing dataset /" + name);
  }
  H5Id create_extendible(const std::string& name, const char* u, size_t cols) {
    const int rank = cols == 0 ? 1 : 2;
    hsize_t dims[2] = {0, cols}, maxd[2] = {H5S_UNLIMITED, cols};
    hsize_t chunk[2] = {cols == 0 ? 256u : 1u, std::max<hsize_t>(cols, 1)};
    H5Id space(H5Screate_simple(rank, dims, maxd), H5Sclose);
    H5Id plist(H5Pcreate(H5P_DATASET_CREATE), H5Pclose);
    if (!plist.valid() || H5Pset_chunk(plist.get(), rank, chunk) < 0) fail("chunking of /" + name);
    H5Id set(H5Dcreate2(file_.get(), name.c_str(), H5T_IEEE_F64LE, space.get(), H5P_DEFAULT, plist.get(),
                        H5P_DEFAULT), H5Dclose);
    if (!set.valid()) fail("cannot create dataset /" + name);
    units(set.get(), u, name);
    return set;
  }
  void append(const H5Id& set, size_t cols, const double* data) {
    const int rank = cols == 0 ? 1 : 2;
    hsize_t size[2] = {rows_ + 1, cols}, start[2] = {rows_, 0}, count[2] = {1, cols};
    if (H5Dset_extent(set.get(), size) < 0) fail("cannot extend a dataset");
    H5Id fspace(H5Dget_space(set.get()), H5Sclose);
    if (!fspace.valid() || H5Sselect_hyperslab(fspace.get(), H5S_SELECT_SET, start, nullptr, count, nullptr) < 0)
      fail("cannot select a row");
    hsize_t mdims[1] = {std::max<hsize_t>(cols, 1)};
    H5Id mspace(H5Screate_simple(1, mdims, nullptr), H5Sclose);
    if (H5Dwrite(set.get(), H5T_NATIVE_DOUBLE, mspace.get(), fspace.get(), H5P_DEFAULT, data) < 0)
      fail("cannot write a frame");
    (void)rank;
  }

  std::string path_;
  H5Id file_;
  std::vector<H5Id> sets_;
  size_t N_ = 0;
  hsize_t rows_ = 0;
};

// A checked text file: the stream state is tested after close.
class TextFile {
 public:
  explicit TextFile(std::string path) : path_(std::move(path)), f_(path_) {
    if (!f_) throw WriteError("cannot write " + path_ + ": " + std::strerror(errno));
    f_ << std::setprecision(10);
  }
  std::ostream& out() { return f_; }
  void close() {
    f_.close();
    if (f_.fail()) throw WriteError("cannot write " + path_ + " (write failed; disk full?)");
  }

 private:
  std::string path_;
  std::ofstream f_;
};

std::string list(const std::vector<std::string>& v) {
  std::string s;
  for (size_t i = 0; i < v.size() && i < 5; ++i) s += (i ? ", " : "") + v[i];
  if (v.size() > 5) s += ", ...";
  return s;
}

bool is_ours(const std::string& name) {
  const auto& names = OutputDir::output_names();
  if (std::find(names.begin(), names.end(), name) != names.end()) return true;
  for (const auto& n : names)
    if (name == n + kPartSuffix) return true;
  return name == kLockName;
}

}  // namespace

namespace {
// Killed by SIGINT/SIGTERM/SIGHUP: the staged files, the lock and a folder the
// run created (if empty) are removed by the handler (unlink/rmdir only, which
// are async-signal-safe), then the signal ends the process as usual.
constexpr int kMaxCleanup = 16;
char g_cleanup[kMaxCleanup][4096];
volatile std::sig_atomic_t g_ncleanup = 0;
char g_created_dir[4096];
volatile std::sig_atomic_t g_dir_created = 0;

extern "C" void cleanup_on_signal(int sig) {
  for (int i = 0; i < g_ncleanup; ++i) ::unlink(g_cleanup[i]);
  if (g_dir_created) ::rmdir(g_created_dir);
  std::signal(sig, SIG_DFL);
  std::raise(sig);
}

void arm_cleanup(const fs::path& dir, bool created, const std::vector<std::string>& names) {
  int n = 0;
  const auto add = [&](const fs::path& p) {
    if (n < kMaxCleanup && p.string().size() < sizeof g_cleanup[0])
      std::snprintf(g_cleanup[n++], sizeof g_cleanup[0], "%s", p.c_str());
  };
  for (const auto& name : names) add(dir / (name + kPartSuffix));
  add(dir / kLockName);
  g_ncleanup = n;
  g_dir_created = 0;
  if (created && dir.string().size() < sizeof g_created_dir) {
    std::snprintf(g_created_dir, sizeof g_created_dir, "%s", dir.c_str());
    g_dir_created = 1;
  }
  for (int sig : {SIGINT, SIGTERM, SIGHUP}) std::signal(sig, cleanup_on_signal);
}

void disarm_cleanup() {
  g_ncleanup = 0;
  g_dir_created = 0;
}
}  // namespace

const std::vector<std::string>& OutputDir::output_names() {
  static const std::vector<std::string> n = {"summary.json", "final_profile.csv", "centre.csv", "profiles.h5",
                                             "conduction_table.csv"};
  return n;
}

OutputDir::OutputDir(const std::string& dir, bool overwrite) : dir_(dir) {
  std::error_code ec;
  const fs::path d(dir);
  const fs::path lock = d / kLockName;
  const auto st = fs::status(d, ec);
  if (fs::exists(st)) {
    if (!fs::is_directory(st))
      throw UsageError("--out: '" + dir + "' exists and is not a directory (a new or empty folder is expected)");
    if (::access(dir.c_str(), W_OK | X_OK) != 0)
      throw UsageError("--out: folder '" + dir + "' is not writable");
    // another run holding the lock
    const int fd = ::open(lock.c_str(), O_RDWR | O_CLOEXEC);
    if (fd >= 0) {
      if (::flock(fd, LOCK_EX | LOCK_NB) != 0) {
        ::close(fd);
        throw UsageError("--out: another laser_drill run is writing into '" + dir + "' (lock file " +
                         lock.string() + " is held); wait for it to end or choose another --out");
      }
      lock_fd_ = fd;
    }
    std::vector<std::string> present, foreign;
    for (const auto& e : fs::directory_iterator(d, ec)) {
      const std::string name = e.path().filename().string();
      if (name == kLockName) continue;
      present.push_back(name);
      if (!is_ours(name)) foreign.push_back(name);
    }
    const auto release = [&] {
      if (lock_fd_ >= 0) ::close(lock_fd_);
      lock_fd_ = -1;
    };
    if (!present.empty() && !overwrite) {
      release();
      throw UsageError("--out: folder '" + dir + "' is not empty (" + list(present) +
                       "); use --overwrite to replace an earlier run's output, or choose a new folder");
    }
    if (!foreign.empty()) {
      release();
      throw UsageError("--out: --overwrite: folder '" + dir + "' holds files laser_drill did not write (" +
                       list(foreign) + "); they are not removed: choose another folder");
    }
  } else {
    fs::path anc = d.has_parent_path() ? d.parent_path() : fs::path(".");
    while (!anc.empty() && !fs::exists(anc, ec)) anc = anc.has_parent_path() && anc.parent_path() != anc
                                                             ? anc.parent_path() : fs::path(".");
    if (!fs::is_directory(anc, ec))
      throw UsageError("--out: cannot create '" + dir + "': '" + anc.string() + "' is not a directory");
    if (::access(anc.c_str(), W_OK | X_OK) != 0)
      throw UsageError("--out: cannot create '" + dir + "': '" + anc.string() + "' is not writable");
    if (!fs::create_directories(d, ec) || ec)
      throw UsageError("--out: cannot create '" + dir + "': " + ec.message());
    created_ = true;
  }
  if (lock_fd_ < 0) {
    lock_fd_ = ::open(lock.c_str(), O_RDWR | O_CREAT | O_CLOEXEC, 0644);
    if (lock_fd_ < 0 || ::flock(lock_fd_, LOCK_EX | LOCK_NB) != 0) {
      const std::string why = lock_fd_ < 0 ? std::strerror(errno) : "held by another run";
      if (lock_fd_ >= 0) ::close(lock_fd_);
      lock_fd_ = -1;
      if (created_) fs::remove_all(d, ec);
      throw UsageError("--out: cannot lock '" + lock.string() + "': " + why);
    }
  }
  arm_cleanup(d, created_, output_names());
  if (overwrite)
    for (const auto& e : fs::directory_iterator(d, ec)) {
      const std::string name = e.path().filename().string();
      if (name != kLockName && is_ours(name)) fs::remove(e.path(), ec);
    }
}

OutputDir::~OutputDir() {
  disarm_cleanup();
  std::error_code ec;
  for (const auto& s : staged_) fs::remove(s, ec);
  const fs::path d(dir_);
  fs::remove(d / kLockName, ec);
  if (lock_fd_ >= 0) ::close(lock_fd_);
  if (created_ && fs::is_empty(d, ec)) fs::remove(d, ec);
}

std::string OutputDir::stage(const std::string& name) {
  const std::string p = (fs::path(dir_) / (name + kPartSuffix)).string();
  if (std::find(staged_.begin(), staged_.end(), p) == staged_.end()) staged_.push_back(p);
  return p;
}

std::unique_ptr<FrameSink> OutputDir::profiles_sink() {
  return std::make_unique<H5FrameWriter>(stage("profiles.h5"));
}

void OutputDir::write_tables(const Config& cfg, const Result& r) {
  {
    TextFile f(stage("final_profile.csv"));
    f.out() << "xi,r_m,t_melt_s,S1net_m,S2_m,S1_vaporized_m,g_m,T_surface_K,pressure_Pa,"
               "melting_rate_m_per_s,vaporization_rate_m_per_s,flow_v_m_per_s\n";
    const Frame& fr = r.final_frame;
    for (size_t i = 0; i < r.xi.size(); ++i)
      f.out() << r.xi[i] << "," << r.xi[i] * cfg.R << "," << r.tau_m_s[i] << "," << fr.S1net[i] << ","
              << fr.S2[i] << "," << fr.S1[i] << "," << fr.g[i] << "," << fr.T[i] << "," << fr.p[i] << ","
              << fr.melt_rate[i] << "," << fr.vap_rate[i] << "," << fr.flow_v[i] << "\n";
    f.close();
  }
  TextFile f(stage("centre.csv"));
  f.out() << "t_s,depth_m,S2_m,g_m,T_K,p_Pa,melting_rate_m_per_s,vaporization_rate_m_per_s,A,u_peak_m_per_s,"
             "melting_rate_xi1node,vaporization_rate_xi1node,flow_v_xi1node,"
             "melting_rate_xi_1,vaporization_rate_xi_1,flow_v_xi_1\n";
  for (const auto& c : r.centre)
    f.out() << c.t << "," << c.depth << "," << c.S2 << "," << c.g << "," << c.T << "," << c.p << ","
            << c.melt_rate << "," << c.vap_rate << "," << c.A << "," << c.u_peak << "," << c.melt_rate_1 << ","
            << c.vap_rate_1 << "," << c.flow_v_1 << "," << c.melt_rate_x1 << "," << c.vap_rate_x1 << ","
            << c.flow_v_x1 << "\n";
  f.close();
}

void OutputDir::commit(const std::string& summary) {
  if (!summary.empty()) {
    TextFile f(stage("summary.json"));
    f.out() << summary;
    f.close();
  }
  // summary.json is renamed last
  std::stable_partition(staged_.begin(), staged_.end(), [](const std::string& s) {
    return fs::path(s).filename().string() != std::string("summary.json") + kPartSuffix;
  });
  for (const auto& s : staged_) {
    std::string final_name = s.substr(0, s.size() - std::strlen(kPartSuffix));
    std::error_code ec;
    fs::rename(s, final_name, ec);
    if (ec) throw WriteError("cannot write " + final_name + ": rename failed: " + ec.message());
  }
  staged_.clear();
}

namespace {
using nlohmann::ordered_json;
ordered_json num_json(double v) { return std::isfinite(v) ? ordered_json(v) : ordered_json(nullptr); }

// summary.json "case": every option that defines the run.
ordered_json case_json(const Config& cfg) {
  const auto num = num_json;
  ordered_json j;
  j["case"] = {{"intensity_W_per_m2", num(cfg.I0)}, {"pulse_s", num(cfg.tp)},      {"radius_m", num(cfg.R)},
               {"model", to_string(cfg.model)},     {"m", num(cfg.m)},             {"xi_p", num(cfg.xi_p)},
               {"Pr", num(cfg.mat.Pr)},             {"solid", to_string(cfg.solid)},
               {"melt_energy", to_string(cfg.melt_energy)},
               {"melt_flow", to_string(cfg.melt_flow)},
               {"melt_heat", cfg.flux_heat() ? "flux" : "ode"},
               {"melt_content", cfg.transient_content() ? "transient" : "steady"},
               {"curvature_factor", cfg.curvature ? to_string(cfg.curvature_form) : "off"},
               {"recoil_fraction_of_p_sat", num(cfg.recoil)},
               {"absorptivity", num(cfg.absorptivity)},
               {"melt_update", cfg.melt_update_name()},
               {"dxi", num(cfg.dxi)},               {"material", cfg.material}};
  return j["case"];
}

// summary.json "groups", "energy_J" and "energy_check".
void energy_json(ordered_json& j, const Result& r) {
  const auto num = num_json;
  const Energy& e = r.energy;
  const Groups& G = r.groups;
  j["groups"] = {{"Ste", num(G.Ste)},         {"N_alpha", num(G.Na)},  {"N_c", num(G.Nc)},    {"k", num(G.k)},
                 {"k_prime", num(G.kprime)},  {"I_prime", num(G.Iprime)}, {"Lambda", num(G.Lambda)},
                 {"H_lv", num(G.Hlv)},        {"N_i", num(G.Ni)},      {"Psi", num(G.Psi)},
                 {"theta_i", num(G.theta_i)}, {"theta_m", num(G.theta_m)}, {"t_scale_s", num(G.t_scale)}};
  const double sum = e.sum();
  j["energy_J"] = {{"laser_exact", num(e.laser_exact)},
                   {"laser_nodal", num(e.laser_nodal)},
                   {"solid_premelt", num(e.solid_premelt)},
                   {"solid_conduction", num(e.solid_conduction)},
                   {"solid_preheat_moving_origin", num(e.solid_preheat)},
                   {"melt_latent", num(e.melt_latent)},
                   {"melt_sensible_vaporized", num(e.melt_sensible)},
                   {"vapour_latent", num(e.vapour_latent)},
                   {"vapour_kinetic", num(e.vapour_kinetic)},
                   {"flow_advected", num(e.flow_advected)},
                   {"melt_heat_content", num(e.melt_content)},
                   {"clamp_defect", num(e.clamp_defect)},
                   {"sum_of_terms", num(sum)},
                   {"relative_imbalance", num(e.laser_exact > 0 ? (sum - e.laser_exact) / e.laser_exact : 0.0)}};
  const PhysicalCheck& pc = r.check;
  j["energy_check"] = {{"H_J_per_kg", num(pc.H)},
                       {"T_s_center_K", num(pc.Ts)},
                       {"removed_rhoH_over_beam", num(pc.removed_over_beam)},
                       {"melted_and_vaporized_over_beam", num(pc.melt_vap_over_beam)},
                       {"worst_node_demand_over_absorbed", num(pc.worst_node_ratio)},
                       {"worst_node_xi", num(pc.worst_node_xi)},
                       {"centre_velocity_over_bound", num(pc.centre_velocity_ratio)},
                       {"holds", pc.holds}};
}
}  // namespace

std::string summary_json(const Config& cfg, const Result& r, double wall) {
  using nlohmann::ordered_json;
  ordered_json j;
  const auto num = [](double v) { return std::isfinite(v) ? ordered_json(v) : ordered_json(nullptr); };
  j["status"] = r.status;
  j["message"] = r.message;
  j["notes"] = r.notes;
  j["causes"] = r.causes;
  j["warnings"] = r.warnings;
  j["T_peak_over_T_critical"] = num(r.T_over_Tc);
  j["t_melt_center_s"] = r.t_melt_center >= 0 ? num(r.t_melt_center) : ordered_json(nullptr);
  j["depth_center_m"] = num(r.depth_center);
  j["volume_removed_m3"] = num(r.volume_removed);
  j["removal_rate_m3_per_s"] = num(r.removal_rate);
  j["T_peak_K"] = num(r.T_peak);
  j["p_peak_Pa"] = num(r.p_peak);
  j["wall_time_s"] = num(wall);
  j["time_step"] = {{"dt_s", num(r.dt)},
                    {"automatic", r.step.automatic},
                    {"companion_dt_s", num(r.step.companion_dt)},
                    {"fine_companion_dt_s", num(r.step.fine_companion_dt)},
                    {"depth_difference_ratio", num(r.step.depth_ratio)},
                    {"volume_difference_ratio", num(r.step.volume_ratio)},
                    {"depth_error_estimate", num(r.step.depth_error)},
                    {"volume_error_estimate", num(r.step.volume_error)},
                    {"grid_companion_dxi", num(r.step.grid_companion_dxi)},
                    {"grid_companion_dt_s", num(r.step.grid_companion_dt)},
                    {"grid_depth_error_estimate", num(r.step.grid_depth_error)},
                    {"grid_volume_error_estimate", num(r.step.grid_volume_error)},
                    {"tol", num(cfg.tol)},
                    {"runs", r.step.runs},
                    {"steps_total", r.step.steps_total},
                    {"reason", r.step.reason}};
  j["t_end_s"] = num(r.t_end);
  j["S2_center_m"] = num(r.S2_center);
  j["melt_thickness_center_m"] = num(r.g_center);
  j["T_surface_center_K"] = num(r.T_center);
  j["volume_vaporized_m3"] = num(r.volume_vaporized);
  j["volume_removed_by_flow_m3"] = num(r.volume_flow);
  j["volume_melted_m3"] = num(r.volume_melted);
  j["melt_balance"] = {{"melted_m3", num(r.volume_melted)},
                       {"vaporized_m3", num(r.volume_vaporized)},
                       {"expelled_over_rim_m3", num(r.volume_expelled)},
                       {"still_molten_m3", num(r.volume_molten)},
                       {"vaporization_cut_m3", num(r.vaporization_cut)},
                       {"relative_residual", num(r.melt_balance)},
                       {"flow_substeps_max", r.flow_substeps_max}};
  j["heat_courant_substeps_max"] = r.heat_substeps_max;
  j["heat_courant_steps_added"] = r.heat_substeps_extra;
  j["u_peak_max_m_per_s"] = num(r.u_peak_max);
  j["A_last"] = num(r.A_last);
  j["xi_melt_edge"] = num(r.xi_melt_edge);
  j["boundary_layer_last_xi"] = num(r.bl_last_xi);
  j["boundary_layer_thicker_than_melt_steps"] = r.bl_thicker_steps;
  j["b2_demand_max"] = num(r.b2_demand_max);
  j["steps"] = r.steps;
  j["nodes"] = r.nodes;
  j["frames"] = r.frames_written;
  j["dt_s"] = num(r.dt);
  j["dtau"] = num(r.dtau);
  j["tau_p"] = num(r.tau_p);
  // the a-priori limit the automatic step takes a quarter of (null for the
  // implicit update), and 2/lambda at its largest along the run (thin layers
  // right after onset; the run-time check fires only when g also oscillates)
  j["max_stable_dt_s"] = r.step.stable_limit > 0 ? num(r.step.stable_limit) : nlohmann::ordered_json(nullptr);
  // the largest --dt accepted with the explicit update (half of the limit above)
  j["max_accepted_dt_s"] = r.step.accepted_limit > 0 ? num(r.step.accepted_limit) : nlohmann::ordered_json(nullptr);
  j["min_2_over_lambda_seen_s"] = num(r.max_stable_dt);
  j["melt_thickness_clamps"] = r.melt_clamps;
  j["melt_rate_clamps"] = r.melt_rate_clamps;
  j["curvature_clamps"] = r.curvature_clamps;
  j["b2_limiter_hits"] = r.b2_clamps;
  j["b2_limiter_content_hits"] = r.b2_content_clamps;
  j["max_interface_residual"] = num(r.max_interface_residual);
  j["case"] = case_json(cfg);
  energy_json(j, r);
  return j.dump(2) + "\n";
}

void write_conduction_table(OutputDir& out) {
  std::vector<double> s;
  for (int k = 0; k <= 200; ++k) s.push_back(1e-3 * std::pow(10.0, k / 50.0));  // 1e-3 .. 10
  CorrectedConduction cc(kTau0OverTauM);
  const std::vector<double> ref = reference_gradient(s);
  TextFile f(out.stage("conduction_table.csv"));
  // gradients per unit theta_i in x = n / sqrt(N_a tau_m); multiply by theta_i/sqrt(N_a tau_m)
  f.out() << "s,stefan_s1,correction_s2,correction_s3,exact,reference_fd,shifted_1tau0,shifted_3tau0,"
             "shifted_flux_continuous,pre_melting\n";
  for (size_t k = 0; k < s.size(); ++k) {
    const double st = 1.0 / std::sqrt(kPi * (s[k] + kTau0OverTauM));
    auto interp = [&](const std::vector<double>& y) {
      const auto& S = cc.s_table();
      size_t j = std::upper_bound(S.begin(), S.end(), s[k]) - S.begin();
      if (j >= S.size()) return y.back();
      const double w = (s[k] - S[j - 1]) / (S[j] - S[j - 1]);
      return (1 - w) * y[j - 1] + w * y[j];
    };
    f.out() << s[k] << "," << st << "," << interp(cc.g2_table()) << "," << interp(cc.g3_table()) << ","
            << cc.gradient(s[k]) << "," << ref[k] << "," << 1.0 / std::sqrt(kPi * (s[k] + kTau0OverTauM)) << ","
            << 1.0 / std::sqrt(kPi * (s[k] + 3 * kTau0OverTauM)) << ","
            << 1.0 / std::sqrt(kPi * (s[k] + 4.0 / (kPi * kPi))) << "," << 0.5 * std::sqrt(kPi) << "\n";
  }
  f.close();
  out.commit("");
}

}  // namespace laser
