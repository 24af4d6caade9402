#include "mpm/hdf5_series.h"

#include <hdf5.h>
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

[[noreturn]] void fail(const std::string &file, const std::string &what) {
  throw std::runtime_error("Hdf5Series: " + file + ": " + what);
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
  long long ok(long long r, const std::string &what) const {
    if (r < 0) fail(file, what + " failed" + h5_detail());
    return r;
  }
  void attr(hid_t loc, const char *name, hid_t ftype, hid_t mtype, hsize_t n, const void *v) const {
    Handle sp(ok(H5Screate_simple(1, &n, nullptr), std::string("dataspace for attribute ") + name), H5Sclose);
    Handle a(ok(H5Acreate2(loc, name, ftype, sp.get(), H5P_DEFAULT, H5P_DEFAULT),
                std::string("creating attribute ") + name), H5Aclose);
    ok(H5Awrite(a.get(), mtype, v), std::string("writing attribute ") + name);
    ok(a.close(), std::string("closing attribute ") + name);
  }
  void dataset(hid_t loc, const std::string &path, const std::vector<hsize_t> &dims, const double *v) const {
    const std::string name = path.substr(path.rfind('/') + 1);
    Handle sp(ok(H5Screate_simple(int(dims.size()), dims.data(), nullptr), "dataspace for " + path), H5Sclose);
    Handle d(ok(H5Dcreate2(loc, name.c_str(), H5T_IEEE_F64LE, sp.get(), H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT),
                "creating dataset " + path), H5Dclose);
    hsize_t count = 1;
    for (hsize_t x : dims) count *= x;
    if (count > 0)
      ok(H5Dwrite(d.get(), H5T_NATIVE_DOUBLE, H5S_ALL, H5S_ALL, H5P_DEFAULT, v), "writing dataset " + path);
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

}  // namespace

Hdf5Series::Hdf5Series(const std::string &prefix) : prefix_(prefix), xmf_path_(prefix + ".xmf") {
  const std::size_t slash = prefix.rfind('/');
  base_ = slash == std::string::npos ? prefix : prefix.substr(slash + 1);
  if (base_.empty()) fail(prefix, "output prefix must name a file, not a directory");
  const std::string dir = slash == std::string::npos ? "." : (slash == 0 ? "/" : prefix.substr(0, slash));
  struct stat st;
  if (stat(dir.c_str(), &st) != 0 || !S_ISDIR(st.st_mode))
    fail(xmf_path_, "output directory '" + dir + "' does not exist");
  if (access(dir.c_str(), W_OK | X_OK) != 0) fail(xmf_path_, "output directory '" + dir + "' is not writable");
  load_existing();
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
  const std::string path = step_path(step);
  const std::string fname = path.substr(path.rfind('/') + 1);
  // ---- validate everything before touching the disk
  if (step < 0) fail(path, "negative step number");
  if (pts.xyz.size() != 3 * pts.n)
    fail(path, "points xyz size " + std::to_string(pts.xyz.size()) + " != 3 x " + std::to_string(pts.n));
  check_fields(path, pts.fields, pts.n, "points", true);
  std::size_t nn = 0;
  if (grid) {
    for (int d = 0; d < 3; ++d)
      if (grid->n[d] < 1) fail(path, "grid node count must be >= 1 in every direction");
    nn = std::size_t(grid->n[0]) * grid->n[1] * grid->n[2];
    check_fields(path, grid->fields, nn, "grid", false);
  }

  // ---- HDF5 step file, written to <file>.tmp and renamed into place
  const std::string tmp = path + ".tmp";
  {
    QuietH5 quiet;
    H5Writer w{path};
    try {
      Handle fapl(w.ok(H5Pcreate(H5P_FILE_ACCESS), "creating file access list"), H5Pclose);
#if H5_VERSION_GE(1, 10, 7)
      // no flock(): it fails on some parallel file systems and blocks concurrent viewers
      w.ok(H5Pset_file_locking(fapl.get(), false, true), "disabling file locking");
#endif
      Handle f(w.ok(H5Fcreate(tmp.c_str(), H5F_ACC_TRUNC, H5P_DEFAULT, fapl.get()), "creating file " + tmp),
               H5Fclose);
      const long long step64 = step;
      w.attr(f.get(), "time", H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, 1, &time);
      w.attr(f.get(), "step", H5T_STD_I64LE, H5T_NATIVE_LLONG, 1, &step64);
      {
        Handle g(w.ok(H5Gcreate2(f.get(), "points", H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT), "creating group /points"),
                 H5Gclose);
        const hsize_t n = pts.n;
        w.dataset(g.get(), "/points/xyz", {n, 3}, pts.xyz.data());
        for (const Field &fl : pts.fields)
          w.dataset(g.get(), "/points/" + fl.name,
                    fl.ncomp == 1 ? std::vector<hsize_t>{n} : std::vector<hsize_t>{n, hsize_t(fl.ncomp)},
                    fl.data.data());
        w.ok(g.close(), "closing group /points");
      }
      if (grid) {
        Handle g(w.ok(H5Gcreate2(f.get(), "grid", H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT), "creating group /grid"),
                 H5Gclose);
        const long long n64[3] = {grid->n[0], grid->n[1], grid->n[2]};
        w.attr(g.get(), "n", H5T_STD_I64LE, H5T_NATIVE_LLONG, 3, n64);
        w.attr(g.get(), "origin", H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, 3, grid->origin);
        w.attr(g.get(), "spacing", H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, 3, grid->spacing);
        std::vector<hsize_t> dims = {hsize_t(grid->n[2]), hsize_t(grid->n[1]), hsize_t(grid->n[0])};
        for (const Field &fl : grid->fields) {
          std::vector<hsize_t> d = dims;
          if (fl.ncomp > 1) d.push_back(hsize_t(fl.ncomp));
          w.dataset(g.get(), "/grid/" + fl.name, d, fl.data.data());
        }
        w.ok(g.close(), "closing group /grid");
      }
      w.ok(f.close(), "closing file " + tmp);
    } catch (...) {
      std::remove(tmp.c_str());
      throw;
    }
  }
  if (std::rename(tmp.c_str(), path.c_str()) != 0) {
    const int err = errno;
    std::remove(tmp.c_str());
    fail(path, std::string("renaming temporary file failed: ") + std::strerror(err));
  }

  // ---- XDMF block for this step
  const std::string n = std::to_string(pts.n);
  std::ostringstream x;
  const bool coll = grid != nullptr || pts.n == 0;  // empty point sets are left out of the index
  const std::string in = coll ? "        " : "      ";
  x << kBegin << "step=\"" << step << "\" time=\"" << num(time) << "\" file=\"" << xml_escape(fname)
    << "\" -->\n";
  if (coll) x << "      <Grid Name=\"step_" << step << "\" GridType=\"Collection\" CollectionType=\"Spatial\">\n"
              << "        <Time Value=\"" << num(time) << "\"/>\n";
  if (pts.n > 0) {
    x << in << "<Grid Name=\"" << "points"
      << "\" GridType=\"Uniform\">\n";
    if (!coll) x << in << "  <Time Value=\"" << num(time) << "\"/>\n";
    x << in << "  <Topology TopologyType=\"Polyvertex\" NumberOfElements=\"" << n << "\" NodesPerElement=\"1\"/>\n"
      << in << "  <Geometry GeometryType=\"XYZ\">\n"
      << in << "    " << data_item(n + " 3", fname + ":/points/xyz") << "\n"
      << in << "  </Geometry>\n";
    for (const Field &fl : pts.fields)
      x << in << "  <Attribute Name=\"" << xml_escape(fl.name) << "\" AttributeType=\"" << attr_type(fl.ncomp)
        << "\" Center=\"Node\">\n"
        << in << "    " << data_item(fl.ncomp == 1 ? n : n + " " + std::to_string(fl.ncomp),
                                     fname + ":/points/" + fl.name) << "\n"
        << in << "  </Attribute>\n";
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
    for (const Field &fl : grid->fields)
      x << in << "  <Attribute Name=\"" << xml_escape(fl.name) << "\" AttributeType=\"" << attr_type(fl.ncomp)
        << "\" Center=\"Node\">\n"
        << in << "    " << data_item(fl.ncomp == 1 ? dims : dims + " " + std::to_string(fl.ncomp),
                                     fname + ":/grid/" + fl.name) << "\n"
        << in << "  </Attribute>\n";
    x << in << "</Grid>\n";
  }
  if (coll) x << "      </Grid>\n";
  x << "      " << kEnd;

  // ---- update the index: replace this step, drop later (abandoned) steps
  std::vector<Entry> old = entries_;
  entries_.erase(std::remove_if(entries_.begin(), entries_.end(), [&](const Entry &e) { return e.step >= step; }),
                 entries_.end());
  entries_.push_back(Entry{step, time, fname, x.str()});
  try {
    write_xmf();
  } catch (...) {
    entries_.swap(old);
    throw;
  }
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
