// Tests for mpm::Hdf5Series (HDF5 + XDMF time-series writer): alone (MPI_COMM_SELF) and with the
// points and grid boxes split over the ranks of MPI_COMM_WORLD (run on 1 and 2 ranks).
#include "mpm/hdf5_series.h"

#include <gtest/gtest.h>
#include <hdf5.h>
#include <mpi.h>
#include <stdlib.h>

#include <filesystem>
#include <functional>
#include <memory>
#include <fstream>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

namespace fs = std::filesystem;
using mpm::Field;
using mpm::GridBlock;
using mpm::Hdf5Series;
using mpm::PointBlock;

namespace {

class TempDir {
 public:
  TempDir() {
    std::string tmpl = ::testing::TempDir();
    if (tmpl.empty() || tmpl.back() != '/') tmpl += '/';
    tmpl += "h5series_XXXXXX";
    std::vector<char> buf(tmpl.begin(), tmpl.end());
    buf.push_back('\0');
    if (!mkdtemp(buf.data())) throw std::runtime_error("mkdtemp failed");
    path_ = buf.data();
  }
  ~TempDir() {
    std::error_code ec;
    fs::remove_all(path_, ec);
  }
  const std::string &path() const { return path_; }
 private:
  std::string path_;
};

std::string slurp(const std::string &p) {
  std::ifstream in(p);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

int count(const std::string &s, const std::string &what) {
  int c = 0;
  for (std::size_t p = s.find(what); p != std::string::npos; p = s.find(what, p + 1)) ++c;
  return c;
}

std::vector<double> seq(std::size_t n, double base) {
  std::vector<double> v(n);
  for (std::size_t i = 0; i < n; ++i) v[i] = base + 0.1 * double(i) + 1.0 / 3.0;
  return v;
}

PointBlock make_points(std::size_t n, double base) {
  PointBlock p;
  p.n = n;
  p.xyz = seq(3 * n, base);
  for (int nc : {1, 3, 6, 9, 4})
    p.fields.push_back(Field{"f" + std::to_string(nc), nc, seq(n * nc, base + nc)});
  return p;
}

GridBlock make_grid(double base) {
  GridBlock g{{3, 2, 4}, {-1.0, 0.5, 0.25}, {0.1, 0.2, 0.3}, {}};
  const std::size_t nn = 3 * 2 * 4;
  g.fields.push_back(Field{"phi", 1, seq(nn, base)});
  g.fields.push_back(Field{"u", 3, seq(3 * nn, base + 7)});
  return g;
}

// Minimal HDF5 reading helpers.
struct File {
  hid_t id;
  explicit File(const std::string &p) : id(H5Fopen(p.c_str(), H5F_ACC_RDONLY, H5P_DEFAULT)) {}
  ~File() { if (id >= 0) H5Fclose(id); }
};

std::vector<double> read_ds(hid_t f, const std::string &path, std::vector<hsize_t> *dims) {
  hid_t d = H5Dopen2(f, path.c_str(), H5P_DEFAULT);
  EXPECT_GE(d, 0) << path;
  if (d < 0) return {};
  hid_t sp = H5Dget_space(d);
  const int rank = H5Sget_simple_extent_ndims(sp);
  dims->assign(rank, 0);
  H5Sget_simple_extent_dims(sp, dims->data(), nullptr);
  const hssize_t n = H5Sget_simple_extent_npoints(sp);
  std::vector<double> v(n);
  if (n > 0) {
    EXPECT_GE(H5Dread(d, H5T_NATIVE_DOUBLE, H5S_ALL, H5S_ALL, H5P_DEFAULT, v.data()), 0);
  }
  H5Sclose(sp);
  H5Dclose(d);
  return v;
}

template <class T>
std::vector<T> read_attr(hid_t loc, const char *name, hid_t mtype, std::size_t n) {
  std::vector<T> v(n);
  hid_t a = H5Aopen(loc, name, H5P_DEFAULT);
  EXPECT_GE(a, 0) << name;
  if (a < 0) return v;
  hid_t sp = H5Aget_space(a);
  EXPECT_EQ(H5Sget_simple_extent_npoints(sp), hssize_t(n)) << name;
  H5Sclose(sp);
  EXPECT_GE(H5Aread(a, mtype, v.data()), 0);
  H5Aclose(a);
  return v;
}

void check_points(hid_t f, const PointBlock &p) {
  std::vector<hsize_t> dims;
  EXPECT_EQ(read_ds(f, "/points/xyz", &dims), p.xyz);
  EXPECT_EQ(dims, (std::vector<hsize_t>{p.n, 3}));
  for (const Field &fl : p.fields) {
    EXPECT_EQ(read_ds(f, "/points/" + fl.name, &dims), fl.data) << fl.name;
    std::vector<hsize_t> want{p.n};
    if (fl.ncomp > 1) want.push_back(fl.ncomp);
    EXPECT_EQ(dims, want) << fl.name;
  }
}

void check_step_file(const std::string &path, long step, double time, const PointBlock &p, const GridBlock *g) {
  File f(path);
  ASSERT_GE(f.id, 0) << path;
  EXPECT_EQ(read_attr<double>(f.id, "time", H5T_NATIVE_DOUBLE, 1)[0], time);
  EXPECT_EQ(read_attr<long long>(f.id, "step", H5T_NATIVE_LLONG, 1)[0], step);
  // time and step are scalars (h5py: int(f.attrs["step"]) works; a 1-element array fails on numpy 2)
  for (const char *name : {"time", "step"}) {
    hid_t a = H5Aopen(f.id, name, H5P_DEFAULT);
    hid_t sp = H5Aget_space(a);
    EXPECT_EQ(H5Sget_simple_extent_type(sp), H5S_SCALAR) << name;
    H5Sclose(sp);
    H5Aclose(a);
  }
  check_points(f.id, p);
  EXPECT_EQ(H5Lexists(f.id, "grid", H5P_DEFAULT) > 0, g != nullptr);
  if (!g) return;
  hid_t grp = H5Gopen2(f.id, "grid", H5P_DEFAULT);
  ASSERT_GE(grp, 0);
  EXPECT_EQ(read_attr<double>(grp, "origin", H5T_NATIVE_DOUBLE, 3), std::vector<double>(g->origin, g->origin + 3));
  EXPECT_EQ(read_attr<double>(grp, "spacing", H5T_NATIVE_DOUBLE, 3),
            std::vector<double>(g->spacing, g->spacing + 3));
  EXPECT_EQ(read_attr<long long>(grp, "n", H5T_NATIVE_LLONG, 3), (std::vector<long long>{3, 2, 4}));
  H5Gclose(grp);
  for (const Field &fl : g->fields) {
    std::vector<hsize_t> dims;
    EXPECT_EQ(read_ds(f.id, "/grid/" + fl.name, &dims), fl.data) << fl.name;
    std::vector<hsize_t> want{hsize_t(g->n[2]), hsize_t(g->n[1]), hsize_t(g->n[0])};
    if (fl.ncomp > 1) want.push_back(fl.ncomp);
    EXPECT_EQ(dims, want) << fl.name;
  }
}

std::string time_str(double t) {
  char b[40];
  snprintf(b, sizeof b, "%.17g", t);
  return b;
}

}  // namespace

TEST(Hdf5Series, WritesStepsWithGridAndReadsBack) {
  TempDir tmp;
  const std::string prefix = tmp.path() + "/run";
  Hdf5Series s(prefix);
  EXPECT_EQ(s.xdmf_path(), prefix + ".xmf");
  const long steps[3] = {0, 100, 200};
  const double times[3] = {0.0, 0.125, 1.0 / 3.0};
  std::vector<PointBlock> pts;
  std::vector<GridBlock> grids;
  for (int i = 0; i < 3; ++i) {
    pts.push_back(make_points(5 + i, 10.0 * i));
    grids.push_back(make_grid(100.0 * i));
    s.write_step(steps[i], times[i], pts[i], &grids[i]);
  }
  EXPECT_TRUE(fs::exists(prefix + "_000000100.h5"));
  for (int i = 0; i < 3; ++i) check_step_file(s.step_path(steps[i]), steps[i], times[i], pts[i], &grids[i]);

  const std::string x = slurp(prefix + ".xmf");
  ASSERT_FALSE(x.empty());
  EXPECT_EQ(count(x, "<Grid "), 1 + 3 * 3);  // temporal + per step (spatial + points + grid)
  EXPECT_EQ(count(x, "<Grid "), count(x, "</Grid>"));
  EXPECT_EQ(count(x, "<Attribute "), count(x, "</Attribute>"));
  EXPECT_EQ(count(x, "<DataItem "), count(x, "</DataItem>"));
  EXPECT_EQ(count(x, "<Xdmf "), 1);
  EXPECT_EQ(count(x, "</Xdmf>"), 1);
  EXPECT_EQ(count(x, "CollectionType=\"Temporal\""), 1);
  EXPECT_EQ(count(x, "CollectionType=\"Spatial\""), 3);
  EXPECT_EQ(count(x, "TopologyType=\"3DCoRectMesh\" Dimensions=\"4 2 3\""), 3);
  EXPECT_EQ(count(x, "TopologyType=\"Polyvertex\""), 3);
  EXPECT_EQ(count(x, "AttributeType=\"Tensor6\""), 3);
  EXPECT_EQ(count(x, "AttributeType=\"Tensor\""), 3);
  EXPECT_EQ(count(x, "AttributeType=\"Matrix\""), 3);
  EXPECT_EQ(count(x, "AttributeType=\"Vector\""), 6);  // points f3 + grid u
  EXPECT_EQ(count(x, ">0.25 0.5 -1</DataItem>"), 3);   // origin in z y x order
  EXPECT_EQ(count(x, ">0.29999999999999999 0.20000000000000001 0.10000000000000001</DataItem>"), 3);
  for (int i = 0; i < 3; ++i) {
    EXPECT_EQ(count(x, "<Time Value=\"" + time_str(times[i]) + "\"/>"), 1) << i;
    const std::string f = fs::path(s.step_path(steps[i])).filename().string();
    EXPECT_EQ(count(x, ">" + f + ":/points/xyz<"), 1) << f;
    EXPECT_EQ(count(x, ">" + f + ":/grid/u<"), 1) << f;
  }
  EXPECT_EQ(x.find(tmp.path()), std::string::npos) << "xmf must reference files by basename";
  EXPECT_FALSE(fs::exists(prefix + ".xmf.tmp"));
  for (auto &e : fs::directory_iterator(tmp.path())) EXPECT_NE(e.path().extension(), ".tmp") << e.path();
  ASSERT_EQ(s.entries().size(), 3u);
  EXPECT_EQ(s.entries()[2].time, times[2]);
}

TEST(Hdf5Series, PointsOnlyStepIsSingleGrid) {
  TempDir tmp;
  Hdf5Series s(tmp.path() + "/p");
  PointBlock p = make_points(4, 1.0);
  s.write_step(7, 0.5, p, nullptr);
  s.write_step(8, 0.75, p, nullptr);
  check_step_file(s.step_path(7), 7, 0.5, p, nullptr);
  const std::string x = slurp(s.xdmf_path());
  EXPECT_EQ(count(x, "<Grid "), 3);
  EXPECT_EQ(count(x, "</Grid>"), 3);
  EXPECT_EQ(count(x, "CollectionType=\"Spatial\""), 0);
  EXPECT_EQ(count(x, "3DCoRectMesh"), 0);
  EXPECT_EQ(count(x, "<Time Value=\"0.75\"/>"), 1);
  EXPECT_EQ(count(x, ">p_000000007.h5:/points/f9<"), 1);
}

TEST(Hdf5Series, RestartAppendsAndReplaces) {
  TempDir tmp;
  const std::string prefix = tmp.path() + "/r";
  PointBlock p = make_points(3, 0.0);
  GridBlock g = make_grid(0.0);
  {
    Hdf5Series s(prefix);
    s.write_step(0, 0.0, p, &g);
    s.write_step(10, 1.0, p, &g);
    s.write_step(20, 2.0, p, nullptr);
  }
  {  // continuation: keep 0,10,20 and append 30
    Hdf5Series s(prefix);
    ASSERT_EQ(s.entries().size(), 3u);
    EXPECT_EQ(s.entries()[1].step, 10);
    EXPECT_EQ(s.entries()[1].time, 1.0);
    EXPECT_EQ(s.entries()[2].file, "r_000000020.h5");
    s.write_step(30, 3.0, p, &g);
    const std::string x = slurp(s.xdmf_path());
    EXPECT_EQ(count(x, "<Grid "), 1 + 3 + 3 + 1 + 3);
    EXPECT_EQ(count(x, "<Grid "), count(x, "</Grid>"));
    for (const char *t : {"0", "1", "2", "3"}) EXPECT_EQ(count(x, "<Time Value=\"" + std::string(t) + "\"/>"), 1);
  }
  {  // restart from step 10: replace 10, drop 20 and 30
    Hdf5Series s(prefix);
    ASSERT_EQ(s.entries().size(), 4u);
    PointBlock p2 = make_points(6, 50.0);
    s.write_step(10, 1.5, p2, &g);
    ASSERT_EQ(s.entries().size(), 2u);
    check_step_file(s.step_path(10), 10, 1.5, p2, &g);
    const std::string x = slurp(s.xdmf_path());
    EXPECT_EQ(count(x, "<Grid "), 1 + 3 + 3);
    EXPECT_EQ(count(x, "<Time Value=\"1.5\"/>"), 1);
    EXPECT_EQ(count(x, "<Time Value=\"1\"/>"), 0);
    EXPECT_EQ(count(x, "r_000000020.h5"), 0);
    EXPECT_EQ(count(x, "r_000000030.h5"), 0);
    EXPECT_EQ(count(x, ">r_000000000.h5:/points/xyz<"), 1);
    s.write_step(11, 1.6, p2, nullptr);  // and continues normally
  }
  Hdf5Series s(prefix);
  ASSERT_EQ(s.entries().size(), 3u);
  EXPECT_EQ(s.entries()[2].step, 11);
  EXPECT_EQ(s.entries()[2].time, 1.6);
  EXPECT_EQ(s.entries()[1].time, 1.5);
}

TEST(Hdf5Series, BadPrefixDirectoryThrows) {
  TempDir tmp;
  const std::string bad = tmp.path() + "/does/not/exist/run";
  try {
    Hdf5Series s(bad);
    s.write_step(0, 0.0, make_points(2, 0.0), nullptr);
    FAIL() << "expected std::runtime_error";
  } catch (const std::runtime_error &e) {
    EXPECT_NE(std::string(e.what()).find(tmp.path() + "/does/not/exist"), std::string::npos) << e.what();
  }
  EXPECT_THROW(Hdf5Series(tmp.path() + "/"), std::runtime_error);
}

TEST(Hdf5Series, Hdf5FailureNamesFileAndKeepsIndex) {
  TempDir tmp;
  Hdf5Series s(tmp.path() + "/e");
  s.write_step(0, 0.0, make_points(2, 0.0), nullptr);
  const std::string before = slurp(s.xdmf_path());
  fs::create_directory(s.step_path(1) + ".tmp");  // H5Fcreate on a directory fails
  try {
    s.write_step(1, 1.0, make_points(2, 0.0), nullptr);
    FAIL() << "expected std::runtime_error";
  } catch (const std::runtime_error &e) {
    EXPECT_NE(std::string(e.what()).find("e_000000001.h5"), std::string::npos) << e.what();
  }
  EXPECT_EQ(slurp(s.xdmf_path()), before);
  EXPECT_EQ(s.entries().size(), 1u);
}

TEST(Hdf5Series, InvalidInputThrowsWithoutWriting) {
  TempDir tmp;
  Hdf5Series s(tmp.path() + "/bad");
  PointBlock p = make_points(3, 0.0);
  p.fields[1].data.pop_back();
  EXPECT_THROW(s.write_step(0, 0.0, p, nullptr), std::runtime_error);
  PointBlock q = make_points(3, 0.0);
  q.fields.push_back(Field{"a/b", 1, {1, 2, 3}});
  EXPECT_THROW(s.write_step(0, 0.0, q, nullptr), std::runtime_error);
  GridBlock g = make_grid(0.0);
  g.fields[0].data.push_back(1.0);
  EXPECT_THROW(s.write_step(0, 0.0, make_points(3, 0.0), &g), std::runtime_error);
  EXPECT_FALSE(fs::exists(s.xdmf_path()));
  EXPECT_TRUE(fs::is_empty(tmp.path()));
}

TEST(Hdf5Series, ForeignXmfIsNotOverwritten) {
  TempDir tmp;
  { std::ofstream(tmp.path() + "/other.xmf") << "<Xdmf></Xdmf>\n"; }
  EXPECT_THROW(Hdf5Series(tmp.path() + "/other"), std::runtime_error);
}

TEST(Hdf5Series, ZeroPoints) {
  TempDir tmp;
  Hdf5Series s(tmp.path() + "/z");
  PointBlock p;
  p.fields.push_back(Field{"rho", 1, {}});
  p.fields.push_back(Field{"v", 3, {}});
  s.write_step(0, 0.0, p, nullptr);
  GridBlock g = make_grid(1.0);
  s.write_step(1, 0.1, p, &g);
  check_step_file(s.step_path(0), 0, 0.0, p, nullptr);
  check_step_file(s.step_path(1), 1, 0.1, p, &g);
  const std::string x = slurp(s.xdmf_path());
  EXPECT_EQ(count(x, "<Grid "), count(x, "</Grid>"));
  EXPECT_EQ(count(x, "<Time Value=\"0.10000000000000001\"/>"), 1);
  EXPECT_EQ(count(x, "3DCoRectMesh"), 1);
  Hdf5Series again(tmp.path() + "/z");
  EXPECT_EQ(again.entries().size(), 2u);
}

// ---- all ranks of MPI_COMM_WORLD write one series together

namespace {

int world_rank() {
  int r;
  MPI_Comm_rank(MPI_COMM_WORLD, &r);
  return r;
}

int world_size() {
  int s;
  MPI_Comm_size(MPI_COMM_WORLD, &s);
  return s;
}

// A folder made by rank 0, its path known to every rank, removed by rank 0.
class SharedDir {
 public:
  SharedDir() {
    if (world_rank() == 0) tmp_.reset(new TempDir);
    std::string p = tmp_ ? tmp_->path() : std::string();
    int len = static_cast<int>(p.size());
    MPI_Bcast(&len, 1, MPI_INT, 0, MPI_COMM_WORLD);
    p.resize(len);
    MPI_Bcast(&p[0], len, MPI_CHAR, 0, MPI_COMM_WORLD);
    path_ = p;
  }
  ~SharedDir() { MPI_Barrier(MPI_COMM_WORLD); }
  const std::string &path() const { return path_; }
 private:
  std::unique_ptr<TempDir> tmp_;
  std::string path_;
};

// rank r's points: rows [first(r), first(r+1)) of the whole set; rank 1 has none
std::size_t first_row(int r) {
  std::size_t n = 0;
  for (int q = 0; q < r; ++q) n += q == 1 ? 0 : 4 + q;
  return n;
}

PointBlock rows_of(const PointBlock &all, std::size_t a, std::size_t b) {
  PointBlock p;
  p.n = b - a;
  p.xyz.assign(all.xyz.begin() + 3 * a, all.xyz.begin() + 3 * b);
  for (const Field &f : all.fields)
    p.fields.push_back(Field{f.name, f.ncomp, std::vector<double>(f.data.begin() + a * f.ncomp, f.data.begin() + b * f.ncomp)});
  return p;
}

// rank r's grid box: z layers [4r/np, 4(r+1)/np) of the 3 x 2 x 4 grid of make_grid
GridBlock box_of(const GridBlock &all, int r, int np) {
  GridBlock g{{all.n[0], all.n[1], all.n[2]}, {all.origin[0], all.origin[1], all.origin[2]},
              {all.spacing[0], all.spacing[1], all.spacing[2]}, {}};
  const int z0 = all.n[2] * r / np, z1 = all.n[2] * (r + 1) / np;
  g.lo[2] = z0;
  g.count[0] = all.n[0];
  g.count[1] = all.n[1];
  g.count[2] = z1 - z0;
  const std::size_t layer = std::size_t(all.n[0]) * all.n[1];
  for (const Field &f : all.fields)
    g.fields.push_back(Field{f.name, f.ncomp, std::vector<double>(f.data.begin() + z0 * layer * f.ncomp,
                                                                  f.data.begin() + z1 * layer * f.ncomp)});
  return g;
}

std::string what_of(const std::function<void()> &fn) {
  try {
    fn();
  } catch (const std::runtime_error &e) {
    return e.what();
  }
  return "(no exception)";
}

}  // namespace

TEST(Hdf5SeriesRanks, EachRankItsRowsAndGridBox) {
  const int me = world_rank(), np = world_size();
  SharedDir dir;
  const PointBlock all = make_points(first_row(np), 3.0);
  const GridBlock grid = make_grid(5.0);
  Hdf5Series s(dir.path() + "/w", MPI_COMM_WORLD);
  const PointBlock mine = rows_of(all, first_row(me), first_row(me + 1));
  const GridBlock box = box_of(grid, me, np);
  s.write_step(3, 0.25, mine, &box);
  s.write_step(4, 0.5, mine, nullptr);
  EXPECT_GT(s.last_write_seconds(), 0.0);
  if (me == 0) {
    check_step_file(s.step_path(3), 3, 0.25, all, &grid);
    check_step_file(s.step_path(4), 4, 0.5, all, nullptr);
    const std::string x = slurp(s.xdmf_path());
    EXPECT_EQ(count(x, "NumberOfElements=\"" + std::to_string(all.n) + "\""), 2);
    EXPECT_EQ(count(x, "<Grid "), 1 + 3 + 1);
    EXPECT_EQ(s.entries().size(), 2u);
    for (auto &e : fs::directory_iterator(dir.path())) EXPECT_NE(e.path().extension(), ".tmp") << e.path();
  }
  Hdf5Series again(dir.path() + "/w", MPI_COMM_WORLD);  // restart: rank 0 reads the index
  if (me == 0) EXPECT_EQ(again.entries().size(), 2u);
}

TEST(Hdf5SeriesRanks, FailureOnOneRankStopsEveryRankWithOneMessage) {
  const int me = world_rank(), np = world_size();
  SharedDir dir;
  Hdf5Series s(dir.path() + "/f", MPI_COMM_WORLD);
  s.write_step(0, 0.0, make_points(2, 0.0), nullptr);
  // the last rank's field has a wrong size: every rank throws that rank's message
  PointBlock p = make_points(2, 0.0);
  if (me == np - 1) p.fields[0].data.pop_back();
  const std::string m1 = what_of([&] { s.write_step(1, 0.1, p, nullptr); });
  EXPECT_NE(m1.find("f_000000001.h5: points field 'f1': data size 1 != 2 x 1"), std::string::npos) << m1;
  // a grid on rank 0 only (np 2), boxes that leave a hole (np 1)
  GridBlock g = make_grid(0.0);
  g.count[0] = 2;
  g.count[1] = 2;
  g.count[2] = 4;
  g.fields.clear();
  const std::string m2 = what_of([&] { s.write_step(2, 0.2, make_points(2, 0.0), me == 0 ? &g : nullptr); });
  EXPECT_NE(m2.find(np > 1 ? "differ from rank 0's" : "the ranks' grid boxes hold 16 nodes, the grid 24"),
            std::string::npos) << m2;
  // HDF5 fails to create the file (a folder in its place): every rank stops, the index is kept
  if (me == 0) fs::create_directory(s.step_path(5) + ".tmp");
  MPI_Barrier(MPI_COMM_WORLD);
  const std::string m3 = what_of([&] { s.write_step(5, 0.5, make_points(2, 0.0), nullptr); });
  EXPECT_NE(m3.find("f_000000005.h5: creating file"), std::string::npos) << m3;
  if (me == 0) {
    EXPECT_EQ(s.entries().size(), 1u);
    EXPECT_FALSE(fs::exists(s.step_path(1)));
    EXPECT_FALSE(fs::exists(s.step_path(5)));
  }
  // and the series goes on
  s.write_step(6, 0.6, make_points(2, 0.0), nullptr);
  if (me == 0) EXPECT_EQ(s.entries().size(), 2u);
  // a missing folder is found by rank 0 and reported on every rank
  const std::string m4 = what_of([&] { Hdf5Series(dir.path() + "/no/such/x", MPI_COMM_WORLD); });
  EXPECT_NE(m4.find("does not exist"), std::string::npos) << m4;
}
