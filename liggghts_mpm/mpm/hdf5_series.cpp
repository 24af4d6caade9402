#include "mpm/hdf5_series.h"

#include <hdf5.h>
#include <mpi.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <sstream>
#include <stdexcept>

namespace mpm {
namespace {

const char *kSignature = "<!-- written by mpm::Hdf5Series -->";
const char *kBegin = "<!-- mpm-step ";
const char *kEnd = "<!-- /mpm-step -->";

std::string message(const std::string &file, const std::string &what) { return "Hdf5Series: " + file + ": " + what; }

[[noreturn]] void fail(const std::string &file, const std::string &what) { throw std::runtime_error(message(file, what)); }

// root's s on every rank of comm (collective)
std::string broadcast(MPI_Comm comm, int root, const std::string &s) {
  int len = static_cast<int>(s.size());
  MPI_Bcast(&len, 1, MPI_INT, root, comm);
  std::string out = s;
  out.resize(len);
  MPI_Bcast(&out[0], len, MPI_CHAR, root, comm);
  return out;
}

// Throws, on every rank of comm, the message of the lowest rank whose msg is not empty; returns
// if all are empty. Every rank calls it at the same point: a failure on one rank stops them all
// there, before the next collective call could wait for it.
void agree(MPI_Comm comm, const std::string &msg) {
  int me, np;
  MPI_Comm_rank(comm, &me);
  MPI_Comm_size(comm, &np);
  int bad = msg.empty() ? np : me, first = np;
  MPI_Allreduce(&bad, &first, 1, MPI_INT, MPI_MIN, comm);
  if (first == np) return;
  throw std::runtime_error(broadcast(comm, first, msg));
}

// The message of the std::runtime_error fn throws, empty if it returns.
template <class Fn>
std::string caught(Fn &&fn) {
  try {
    fn();
  } catch (const std::runtime_error &e) {
    return e.what();
  }
  return {};
}

// Collects the HDF5 error stack descriptions (auto printing is switched off).
std::string h5_detail() {
  std::string msg;
  H5Ewalk2(H5E_DEFAULT, H5E_WALK_DOWNWARD,
           [](unsigned, const H5E_error2_t *e, void *d) -> herr_t {
             auto *s = static_cast<std::string *>(d);
             if (e->desc && *e->desc && s->size() < 400) {
               s->append(s->empty() ? " (" : "; ").append(e->desc);
             }
             return 0;
           },
           &msg);
  H5Eclear2(H5E_DEFAULT);
  for (char &c : msg)
    if (c == '\n' || c == '\r') c = ' ';
  return msg.empty() ? msg : msg + ")";
}

// Disables HDF5's automatic error printing for this scope, restores afterwards.
struct QuietH5 {
  H5E_auto2_t func = nullptr;
  void *data = nullptr;
  QuietH5() {
    H5Eget_auto2(H5E_DEFAULT, &func, &data);
    H5Eset_auto2(H5E_DEFAULT, nullptr, nullptr);
  }
  ~QuietH5() { H5Eset_auto2(H5E_DEFAULT, func, data); }
};

// Owning hid_t with its close function.
class Handle {
 public:
  Handle(hid_t id, herr_t (*close)(hid_t)) : id_(id), close_(close) {}
  ~Handle() { if (id_ >= 0) close_(id_); }
  Handle(const Handle &) = delete;
  Handle &operator=(const Handle &) = delete;
  hid_t get() const { return id_; }
  herr_t close() { herr_t r = id_ >= 0 ? close_(id_) : 0; id_ = -1; return r; }
 private:
  hid_t id_;
  herr_t (*close_)(hid_t);
};

struct H5Writer {
  std::string file;  // for messages
  MPI_Comm comm;     // the ranks that make every HDF5 call together (MPI-IO) or MPI_COMM_SELF
  long long ok(long long r, const std::string &what) const {
    agree(comm, r < 0 ? message(file, what + " failed" + h5_detail()) : std::string());
    return r;
  }
  // n values; n = 0: one value as a scalar (dataspace H5S_SCALAR: int(f.attrs[name]) in h5py)
  void attr(hid_t loc, const char *name, hid_t ftype, hid_t mtype, hsize_t n, const void *v) const {
    Handle sp(ok(n == 0 ? H5Screate(H5S_SCALAR) : H5Screate_simple(1, &n, nullptr),
                 std::string("dataspace for attribute ") + name),
              H5Sclose);
    Handle a(ok(H5Acreate2(loc, name, ftype, sp.get(), H5P_DEFAULT, H5P_DEFAULT),
                std::string("creating attribute ") + name), H5Aclose);
    ok(H5Awrite(a.get(), mtype, v), std::string("writing attribute ") + name);
    ok(a.close(), std::string("closing attribute ") + name);
  }
  // Data set of dims; this rank writes v into the box start, count (its rows, its grid nodes).
  void dataset(hid_t loc, const std::string &path, const std::vector<hsize_t> &dims, const std::vector<hsize_t> &start,
               const std::vector<hsize_t> &count, const double *v) const {
    const std::string name = path.substr(path.rfind('/') + 1);
    const int rank = static_cast<int>(dims.size());
    Handle sp(ok(H5Screate_simple(rank, dims.data(), nullptr), "dataspace for " + path), H5Sclose);
    Handle dcpl(ok(H5Pcreate(H5P_DATASET_CREATE), "creating property list for " + path), H5Pclose);
#ifdef MPM_HDF5_PARALLEL
    // the ranks' boxes tile the data set: no fill values written before the data
    ok(H5Pset_fill_time(dcpl.get(), H5D_FILL_TIME_NEVER), "setting the fill time of " + path);
#endif
    Handle d(ok(H5Dcreate2(loc, name.c_str(), H5T_IEEE_F64LE, sp.get(), H5P_DEFAULT, dcpl.get(), H5P_DEFAULT),
                "creating dataset " + path), H5Dclose);
    hsize_t total = 1, mine = 1;
    for (int i = 0; i < rank; ++i) {
      total *= dims[i];
      mine *= count[i];
    }
    if (total > 0) {  // the same on every rank
      const hsize_t one = 1;
      Handle ms(ok(H5Screate_simple(mine > 0 ? rank : 1, mine > 0 ? count.data() : &one, nullptr),
                   "memory dataspace for " + path), H5Sclose);
      // one ok() on every rank: each is an agreement of all ranks
      ok(mine > 0 ? H5Sselect_hyperslab(sp.get(), H5S_SELECT_SET, start.data(), nullptr, count.data(), nullptr)
                  : std::min(H5Sselect_none(sp.get()), H5Sselect_none(ms.get())),
         "selecting this rank's part of " + path);
      Handle xfer(ok(H5Pcreate(H5P_DATASET_XFER), "creating transfer list for " + path), H5Pclose);
#ifdef MPM_HDF5_PARALLEL
      ok(H5Pset_dxpl_mpio(xfer.get(), H5FD_MPIO_COLLECTIVE), "collective transfer for " + path);
#endif
      const double dummy = 0.0;
      ok(H5Dwrite(d.get(), H5T_NATIVE_DOUBLE, ms.get(), sp.get(), xfer.get(), mine > 0 ? v : &dummy),
         "writing dataset " + path);
    }
    ok(d.close(), "closing dataset " + path);
  }
};

std::string xml_escape(const std::string &s) {
  std::string r;
  for (char c : s) {
    switch (c) {
      case '&': r += "&amp;"; break;
      case '<': r += "&lt;"; break;
      case '>': r += "&gt;"; break;
      case '"': r += "&quot;"; break;
      default: r += c;
    }
  }
  return r;
}

std::string num(double v) {
  char buf[40];
  std::snprintf(buf, sizeof buf, "%.17g", v);
  return buf;
}

const char *attr_type(int ncomp) {
  switch (ncomp) {
    case 1: return "Scalar";
    case 3: return "Vector";
    case 6: return "Tensor6";
    case 9: return "Tensor";
    default: return "Matrix";
  }
}

std::string data_item(const std::string &dims, const std::string &ref) {
  return "<DataItem Dimensions=\"" + dims + "\" NumberType=\"Float\" Precision=\"8\" Format=\"HDF\">" +
         xml_escape(ref) + "</DataItem>";
}

void check_fields(const std::string &file, const std::vector<Field> &fields, std::size_t count,
                  const char *where, bool points) {
  for (std::size_t i = 0; i < fields.size(); ++i) {
    const Field &f = fields[i];
    const std::string id = std::string(where) + " field '" + f.name + "'";
    if (f.name.empty() || f.name == "." || f.name == ".." || f.name.find_first_of("/:") != std::string::npos)
      fail(file, "invalid " + id + " name");
    if (points && f.name == "xyz") fail(file, id + ": name 'xyz' is reserved");
    for (std::size_t j = 0; j < i; ++j)
      if (fields[j].name == f.name) fail(file, "duplicate " + id);
    if (f.ncomp < 1) fail(file, id + ": ncomp must be >= 1");
    if (f.data.size() != count * std::size_t(f.ncomp))
      fail(file, id + ": data size " + std::to_string(f.data.size()) + " != " +
                     std::to_string(count) + " x " + std::to_string(f.ncomp));
  }
}

// One HDF5 step file: attributes, this rank's points (rows offset.. of n_all) and its box of grid
// nodes (lo, cnt). comm: the ranks that write it together (MPI-IO), or MPI_COMM_SELF alone.
void write_file(const std::string &tmp, const std::string &path, MPI_Comm comm, long step, double time,
                const PointBlock &pts, hsize_t n_all, hsize_t offset, const GridBlock *grid, const int lo[3],
                const int cnt[3]) {
  QuietH5 quiet;
  H5Writer w{path, comm};
  Handle fapl(w.ok(H5Pcreate(H5P_FILE_ACCESS), "creating file access list"), H5Pclose);
#if H5_VERSION_GE(1, 10, 7)
  // no flock(): it fails on some parallel file systems and blocks concurrent viewers
  w.ok(H5Pset_file_locking(fapl.get(), false, true), "disabling file locking");
#endif
#ifdef MPM_HDF5_PARALLEL
  w.ok(H5Pset_fapl_mpio(fapl.get(), comm, MPI_INFO_NULL), "selecting MPI-IO");
#endif
  Handle f(w.ok(H5Fcreate(tmp.c_str(), H5F_ACC_TRUNC, H5P_DEFAULT, fapl.get()), "creating file " + tmp), H5Fclose);
  const long long step64 = step;
  w.attr(f.get(), "time", H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, 0, &time);
  w.attr(f.get(), "step", H5T_STD_I64LE, H5T_NATIVE_LLONG, 0, &step64);
  {
    Handle g(w.ok(H5Gcreate2(f.get(), "points", H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT), "creating group /points"),
             H5Gclose);
    const hsize_t n = pts.n;
    w.dataset(g.get(), "/points/xyz", {n_all, 3}, {offset, 0}, {n, 3}, pts.xyz.data());
    for (const Field &fl : pts.fields) {
      const hsize_t nc = hsize_t(fl.ncomp);
      if (fl.ncomp == 1)
        w.dataset(g.get(), "/points/" + fl.name, {n_all}, {offset}, {n}, fl.data.data());
      else
        w.dataset(g.get(), "/points/" + fl.name, {n_all, nc}, {offset, 0}, {n, nc}, fl.data.data());
    }
    w.ok(g.close(), "closing group /points");
  }
  if (grid) {
    Handle g(w.ok(H5Gcreate2(f.get(), "grid", H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT), "creating group /grid"),
             H5Gclose);
    const long long n64[3] = {grid->n[0], grid->n[1], grid->n[2]};
    w.attr(g.get(), "n", H5T_STD_I64LE, H5T_NATIVE_LLONG, 3, n64);
    w.attr(g.get(), "origin", H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, 3, grid->origin);
    w.attr(g.get(), "spacing", H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, 3, grid->spacing);
    const std::vector<hsize_t> dims = {hsize_t(grid->n[2]), hsize_t(grid->n[1]), hsize_t(grid->n[0])};
    const std::vector<hsize_t> start = {hsize_t(lo[2]), hsize_t(lo[1]), hsize_t(lo[0])};
    const std::vector<hsize_t> count = {hsize_t(cnt[2]), hsize_t(cnt[1]), hsize_t(cnt[0])};
    for (const Field &fl : grid->fields) {
      std::vector<hsize_t> d = dims, s = start, c = count;
      if (fl.ncomp > 1) {
        d.push_back(hsize_t(fl.ncomp));
        s.push_back(0);
        c.push_back(hsize_t(fl.ncomp));
      }
      w.dataset(g.get(), "/grid/" + fl.name, d, s, c, fl.data.data());
    }
    w.ok(g.close(), "closing group /grid");
  }
  w.ok(f.close(), "closing file " + tmp);
}

// This step's block of the XDMF index (between marker comments), for n_all points in all.
std::string step_block(long step, double time, const std::string &fname, std::size_t n_all,
                       const std::vector<Field> &pfields, const GridBlock *grid) {
  const std::string n = std::to_string(n_all);
  std::ostringstream x;
  const bool coll = grid != nullptr || n_all == 0;  // empty point sets are left out of the index
  const std::string in = coll ? "        " : "      ";
  x << kBegin << "step=\"" << step << "\" time=\"" << num(time) << "\" file=\"" << xml_escape(fname)
    << "\" -->\n";
  // a node-centred field of group (points, grid) with dims entries (and ncomp components each)
  auto attribute = [&](const Field &fl, const std::string &dims, const char *group) {
    x << in << "  <Attribute Name=\"" << xml_escape(fl.name) << "\" AttributeType=\"" << attr_type(fl.ncomp)
      << "\" Center=\"Node\">\n"
      << in << "    " << data_item(fl.ncomp == 1 ? dims : dims + " " + std::to_string(fl.ncomp),
                                   fname + ":/" + group + "/" + fl.name) << "\n"
      << in << "  </Attribute>\n";
  };
  if (coll) x << "      <Grid Name=\"step_" << step << "\" GridType=\"Collection\" CollectionType=\"Spatial\">\n"
              << "        <Time Value=\"" << num(time) << "\"/>\n";
  if (n_all > 0) {
    x << in << "<Grid Name=\"" << "points"
      << "\" GridType=\"Uniform\">\n";
    if (!coll) x << in << "  <Time Value=\"" << num(time) << "\"/>\n";
    x << in << "  <Topology TopologyType=\"Polyvertex\" NumberOfElements=\"" << n << "\" NodesPerElement=\"1\"/>\n"
      << in << "  <Geometry GeometryType=\"XYZ\">\n"
      << in << "    " << data_item(n + " 3", fname + ":/points/xyz") << "\n"
      << in << "  </Geometry>\n";
    for (const Field &fl : pfields) attribute(fl, n, "points");
    x << in << "</Grid>\n";
  }
  if (grid) {
    const std::string dims =
        std::to_string(grid->n[2]) + " " + std::to_string(grid->n[1]) + " " + std::to_string(grid->n[0]);
    auto zyx = [](const double *v) { return num(v[2]) + " " + num(v[1]) + " " + num(v[0]); };
    x << in << "<Grid Name=\"grid\" GridType=\"Uniform\">\n"
      << in << "  <Topology TopologyType=\"3DCoRectMesh\" Dimensions=\"" << dims << "\"/>\n"
      << in << "  <Geometry GeometryType=\"ORIGIN_DXDYDZ\">\n"
      << in << "    <DataItem Dimensions=\"3\" NumberType=\"Float\" Precision=\"8\" Format=\"XML\">"
      << zyx(grid->origin) << "</DataItem>\n"
      << in << "    <DataItem Dimensions=\"3\" NumberType=\"Float\" Precision=\"8\" Format=\"XML\">"
      << zyx(grid->spacing) << "</DataItem>\n"
      << in << "  </Geometry>\n";
    for (const Field &fl : grid->fields) attribute(fl, dims, "grid");
    x << in << "</Grid>\n";
  }
  if (coll) x << "      </Grid>\n";
  x << "      " << kEnd;
  return x.str();
}

// What every rank must give alike: step, time, the fields and the grid.
std::string layout(long step, double time, const PointBlock &pts, const GridBlock *grid) {
  std::ostringstream os;
  os << step << ' ' << num(time) << " points";
  for (const Field &f : pts.fields) os << ' ' << f.name << ':' << f.ncomp;
  if (grid) {
    os << " grid " << grid->n[0] << ' ' << grid->n[1] << ' ' << grid->n[2];
    for (int d = 0; d < 3; ++d) os << ' ' << num(grid->origin[d]) << ' ' << num(grid->spacing[d]);
    for (const Field &f : grid->fields) os << ' ' << f.name << ':' << f.ncomp;
  }
  return os.str();
}

#ifndef MPM_HDF5_PARALLEL
// rows of all ranks on rank 0, in rank order (empty elsewhere)
std::vector<double> gather_rows(const std::vector<double> &mine, MPI_Comm comm) {
  int me, np;
  MPI_Comm_rank(comm, &me);
  MPI_Comm_size(comm, &np);
  int n = static_cast<int>(mine.size());
  std::vector<int> counts(np), displs(np, 0);
  MPI_Gather(&n, 1, MPI_INT, counts.data(), 1, MPI_INT, 0, comm);
  std::vector<double> all;
  if (me == 0) {
    for (int q = 1; q < np; ++q) displs[q] = displs[q - 1] + counts[q - 1];
    all.resize(displs.back() + counts.back());
  }
  MPI_Gatherv(mine.data(), n, MPI_DOUBLE, all.data(), counts.data(), displs.data(), MPI_DOUBLE, 0, comm);
  return all;
}

PointBlock gather_points(const PointBlock &p, MPI_Comm comm) {
  PointBlock all;
  all.xyz = gather_rows(p.xyz, comm);
  all.n = all.xyz.size() / 3;
  for (const Field &f : p.fields) all.fields.push_back(Field{f.name, f.ncomp, gather_rows(f.data, comm)});
  return all;
}

// The boxes (lo, cnt) of all ranks placed into the whole grid on rank 0.
GridBlock gather_grid(const GridBlock &g, const int lo[3], const int cnt[3], MPI_Comm comm) {
  int me, np;
  MPI_Comm_rank(comm, &me);
  MPI_Comm_size(comm, &np);
  GridBlock all{{g.n[0], g.n[1], g.n[2]},
                {g.origin[0], g.origin[1], g.origin[2]},
                {g.spacing[0], g.spacing[1], g.spacing[2]},
                {}};
  const int mine[6] = {lo[0], lo[1], lo[2], cnt[0], cnt[1], cnt[2]};
  std::vector<int> boxes(6 * np);
  MPI_Gather(mine, 6, MPI_INT, boxes.data(), 6, MPI_INT, 0, comm);
  const std::size_t nn = std::size_t(g.n[0]) * g.n[1] * g.n[2];
  for (const Field &f : g.fields) {
    const std::vector<double> rows = gather_rows(f.data, comm);
    const std::size_t nc = std::size_t(f.ncomp);
    all.fields.push_back(Field{f.name, f.ncomp, std::vector<double>(me == 0 ? nn * nc : 0, 0.0)});
    std::vector<double> &out = all.fields.back().data;
    std::size_t r = 0;
    for (int q = 0; q < np && me == 0; ++q) {
      const int *b = &boxes[6 * q];
      for (int k = b[2]; k < b[2] + b[5]; ++k)
        for (int j = b[1]; j < b[1] + b[4]; ++j)
          for (int i = b[0]; i < b[0] + b[3]; ++i, r += nc)
            std::copy(&rows[r], &rows[r] + nc, &out[((std::size_t(k) * g.n[1] + j) * g.n[0] + i) * nc]);
    }
  }
  return all;
}
#endif

}  // namespace

Hdf5Series::Hdf5Series(const std::string &prefix, MPI_Comm comm)
    : prefix_(prefix), xmf_path_(prefix + ".xmf"), comm_(comm) {
  MPI_Comm_rank(comm_, &me_);
  MPI_Comm_size(comm_, &nprocs_);
  const std::size_t slash = prefix.rfind('/');
  base_ = slash == std::string::npos ? prefix : prefix.substr(slash + 1);
  std::string err;
  if (me_ == 0)  // the index is rank 0's
    err = caught([&] {
      if (base_.empty()) fail(prefix, "output prefix must name a file, not a directory");
      const std::string dir = slash == std::string::npos ? "." : (slash == 0 ? "/" : prefix.substr(0, slash));
      struct stat st;
      if (stat(dir.c_str(), &st) != 0 || !S_ISDIR(st.st_mode))
        fail(xmf_path_, "output directory '" + dir + "' does not exist");
      if (access(dir.c_str(), W_OK | X_OK) != 0) fail(xmf_path_, "output directory '" + dir + "' is not writable");
      load_existing();
    });
  agree(comm_, err);
}

std::string Hdf5Series::step_path(long step) const {
  char buf[32];
  std::snprintf(buf, sizeof buf, "_%09ld.h5", step);
  return prefix_ + buf;
}

void Hdf5Series::load_existing() {
  std::ifstream in(xmf_path_, std::ios::binary);
  if (!in) {
    if (access(xmf_path_.c_str(), F_OK) == 0) fail(xmf_path_, "cannot read existing index file");
    return;  // new series
  }
  std::stringstream ss;
  ss << in.rdbuf();
  const std::string text = ss.str();
  if (text.find(kSignature) == std::string::npos)
    fail(xmf_path_, "existing file was not written by Hdf5Series; refusing to overwrite it");
  for (std::size_t pos = text.find(kBegin); pos != std::string::npos; pos = text.find(kBegin, pos)) {
    const std::size_t end = text.find(kEnd, pos);
    const std::size_t head_end = text.find("-->", pos);
    if (end == std::string::npos || head_end > end) fail(xmf_path_, "corrupt step block in existing index");
    const std::string head = text.substr(pos, head_end - pos);
    auto value = [&](const char *key) {
      const std::size_t k = head.find(std::string(key) + "=\"");
      if (k == std::string::npos) fail(xmf_path_, std::string("step block without ") + key);
      const std::size_t b = k + std::strlen(key) + 2;
      return head.substr(b, head.find('"', b) - b);
    };
    Entry e;
    e.step = std::strtol(value("step").c_str(), nullptr, 10);
    e.time = std::strtod(value("time").c_str(), nullptr);
    e.file = value("file");
    e.xml = text.substr(pos, end + std::strlen(kEnd) - pos);
    entries_.push_back(std::move(e));
    pos = end;
  }
}

void Hdf5Series::write_step(long step, double time, const PointBlock &pts, const GridBlock *grid) {
  const double t0 = MPI_Wtime();
  const std::string path = step_path(step);
  const std::string fname = path.substr(path.rfind('/') + 1);
  // ---- validate everything (each rank its part, then together) before touching the disk
  int lo[3] = {0, 0, 0}, cnt[3] = {0, 0, 0};
  unsigned long long mine[2] = {pts.n, 0}, all[2] = {0, 0}, offset = 0;  // points, grid nodes
  agree(comm_, caught([&] {
          if (step < 0) fail(path, "negative step number");
          if (pts.xyz.size() != 3 * pts.n)
            fail(path, "points xyz size " + std::to_string(pts.xyz.size()) + " != 3 x " + std::to_string(pts.n));
          check_fields(path, pts.fields, pts.n, "points", true);
          if (!grid) return;
          for (int d = 0; d < 3; ++d) {
            if (grid->n[d] < 1) fail(path, "grid node count must be >= 1 in every direction");
            lo[d] = grid->count[d] < 0 ? 0 : grid->lo[d];
            cnt[d] = grid->count[d] < 0 ? grid->n[d] : grid->count[d];
            if (lo[d] < 0 || lo[d] + cnt[d] > grid->n[d]) fail(path, "grid box outside the grid");
          }
          mine[1] = static_cast<unsigned long long>(cnt[0]) * cnt[1] * cnt[2];
          check_fields(path, grid->fields, mine[1], "grid", false);
        }));
  if (nprocs_ > 1) {
    const std::string sig = layout(step, time, pts, grid), sig0 = broadcast(comm_, 0, sig);
    agree(comm_, sig == sig0 ? std::string() : message(path, "step, time, fields or grid differ from rank 0's"));
  }
  MPI_Allreduce(mine, all, 2, MPI_UNSIGNED_LONG_LONG, MPI_SUM, comm_);
  MPI_Exscan(&mine[0], &offset, 1, MPI_UNSIGNED_LONG_LONG, MPI_SUM, comm_);
  if (me_ == 0) offset = 0;  // MPI_Exscan leaves rank 0's undefined
  const std::size_t n_all = all[0];
  if (grid && all[1] != std::size_t(grid->n[0]) * grid->n[1] * grid->n[2])  // the same on every rank
    fail(path, "the ranks' grid boxes hold " + std::to_string(all[1]) + " nodes, the grid " +
                   std::to_string(std::size_t(grid->n[0]) * grid->n[1] * grid->n[2]));

  // ---- HDF5 step file, written to <file>.tmp and renamed into place
  const std::string tmp = path + ".tmp";
  std::string err;
#ifdef MPM_HDF5_PARALLEL
  // every rank its rows of the same data sets; write_file's checks stop all ranks together
  err = caught([&] { write_file(tmp, path, comm_, step, time, pts, n_all, offset, grid, lo, cnt); });
#else
  if (nprocs_ > 1) {  // rank 0 gathers and writes alone
    const PointBlock pall = gather_points(pts, comm_);
    const GridBlock gall = grid ? gather_grid(*grid, lo, cnt, comm_) : GridBlock{};
    const int whole[3] = {grid ? grid->n[0] : 0, grid ? grid->n[1] : 0, grid ? grid->n[2] : 0}, zero[3] = {0, 0, 0};
    if (me_ == 0)
      err = caught([&] {
        write_file(tmp, path, MPI_COMM_SELF, step, time, pall, n_all, 0, grid ? &gall : nullptr, zero, whole);
      });
  } else {
    err = caught([&] { write_file(tmp, path, MPI_COMM_SELF, step, time, pts, n_all, 0, grid, lo, cnt); });
  }
#endif
  if (me_ == 0 && err.empty() && std::rename(tmp.c_str(), path.c_str()) != 0)
    err = message(path, std::string("renaming temporary file failed: ") + std::strerror(errno));
  MPI_Barrier(comm_);  // every rank has closed the file (or failed) before rank 0 removes it
  if (me_ == 0 && !err.empty()) std::remove(tmp.c_str());
  agree(comm_, err);

  // ---- the index (rank 0): replace this step, drop later (abandoned) steps
  if (me_ == 0) {
    std::vector<Entry> old = entries_;
    entries_.erase(std::remove_if(entries_.begin(), entries_.end(), [&](const Entry &e) { return e.step >= step; }),
                   entries_.end());
    entries_.push_back(Entry{step, time, fname, step_block(step, time, fname, n_all, pts.fields, grid)});
    err = caught([&] { write_xmf(); });
    if (!err.empty()) entries_.swap(old);
  }
  agree(comm_, err);
  last_seconds_ = MPI_Wtime() - t0;
}

void Hdf5Series::write_xmf() const {
  std::string s =
      "<?xml version=\"1.0\" ?>\n"
      "<!DOCTYPE Xdmf SYSTEM \"Xdmf.dtd\" []>\n";
  s += kSignature;
  s += "\n<Xdmf Version=\"3.0\" xmlns:xi=\"http://www.w3.org/2001/XInclude\">\n"
       "  <Domain>\n"
       "    <Grid Name=\"" + xml_escape(base_) + "\" GridType=\"Collection\" CollectionType=\"Temporal\">\n";
  for (const Entry &e : entries_) s += "      " + e.xml + "\n";
  s += "    </Grid>\n  </Domain>\n</Xdmf>\n";

  const std::string tmp = xmf_path_ + ".tmp";
  std::FILE *f = std::fopen(tmp.c_str(), "wb");
  if (!f) fail(tmp, std::string("cannot open for writing: ") + std::strerror(errno));
  const bool good = std::fwrite(s.data(), 1, s.size(), f) == s.size() && std::fflush(f) == 0 &&
                    fsync(fileno(f)) == 0;
  const int err = errno;
  if (std::fclose(f) != 0 || !good) {
    std::remove(tmp.c_str());
    fail(tmp, std::string("write failed: ") + std::strerror(good ? errno : err));
  }
  if (std::rename(tmp.c_str(), xmf_path_.c_str()) != 0) {
    const int e2 = errno;
    std::remove(tmp.c_str());
    fail(xmf_path_, std::string("renaming ") + tmp + " failed: " + std::strerror(e2));
  }
}

}  // namespace mpm
