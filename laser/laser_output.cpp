#include "laser_output.h"

#include <hdf5.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <sstream>
#include <stdexcept>

namespace laser {

namespace {

std::string num(double v) {
  if (!std::isfinite(v)) return "null";
  std::ostringstream o;
  o << std::setprecision(10) << v;
  return o.str();
}

std::string quote(const std::string& s) {
  std::string o = "\"";
  for (char c : s) {
    if (c == '"' || c == '\\') o += '\\';
    o += c;
  }
  return o + "\"";
}

void write_dataset(hid_t file, const std::string& name, const std::vector<double>& data,
                   hsize_t rows, hsize_t cols) {
  hsize_t dims[2] = {rows, cols};
  const int rank = cols == 0 ? 1 : 2;
  hid_t space = H5Screate_simple(rank, dims, nullptr);
  hid_t set = H5Dcreate2(file, name.c_str(), H5T_IEEE_F64LE, space, H5P_DEFAULT, H5P_DEFAULT,
                         H5P_DEFAULT);
  if (set < 0) throw std::runtime_error("HDF5: cannot create dataset " + name);
  if (!data.empty() && H5Dwrite(set, H5T_NATIVE_DOUBLE, H5S_ALL, H5S_ALL, H5P_DEFAULT, data.data()) < 0)
    throw std::runtime_error("HDF5: cannot write dataset " + name);
  H5Dclose(set);
  H5Sclose(space);
}

void write_h5(const std::string& path, const Result& r) {
  hid_t file = H5Fcreate(path.c_str(), H5F_ACC_TRUNC, H5P_DEFAULT, H5P_DEFAULT);
  if (file < 0) throw std::runtime_error("cannot create " + path);
  const hsize_t F = r.frames.size(), N = r.xi.size();
  write_dataset(file, "/xi", r.xi, N, 0);
  write_dataset(file, "/t_melt_s", r.tau_m_s, N, 0);
  std::vector<double> t, A, up;
  for (const auto& f : r.frames) { t.push_back(f.t); A.push_back(f.A); up.push_back(f.u_peak); }
  write_dataset(file, "/time_s", t, F, 0);
  write_dataset(file, "/A", A, F, 0);
  write_dataset(file, "/u_peak_m_per_s", up, F, 0);
  auto field = [&](const char* name, std::vector<double> Frame::*member) {
    std::vector<double> buf;
    buf.reserve(F * N);
    for (const auto& f : r.frames) buf.insert(buf.end(), (f.*member).begin(), (f.*member).end());
    write_dataset(file, name, buf, F, N);
  };
  field("/S1net_m", &Frame::S1net);
  field("/S2_m", &Frame::S2);
  field("/S1_vaporized_m", &Frame::S1);
  field("/g_m", &Frame::g);
  field("/theta_sat", &Frame::theta_sat);
  field("/T_surface_K", &Frame::T);
  field("/pressure_Pa", &Frame::p);
  field("/melting_rate_m_per_s", &Frame::melt_rate);
  field("/vaporization_rate_m_per_s", &Frame::vap_rate);
  field("/flow_v_m_per_s", &Frame::flow_v);
  field("/b2", &Frame::b2);
  H5Fclose(file);
}

}  // namespace

std::string summary_json(const Config& cfg, const Result& r, double wall) {
  const Energy& e = r.energy;
  std::ostringstream o;
  o << "{\n";
  o << "  \"status\": " << quote(r.status) << ",\n";
  o << "  \"message\": " << quote(r.message) << ",\n";
  o << "  \"t_melt_center_s\": " << (r.t_melt_center >= 0 ? num(r.t_melt_center) : "null") << ",\n";
  o << "  \"depth_center_m\": " << num(r.depth_center) << ",\n";
  o << "  \"volume_removed_m3\": " << num(r.volume_removed) << ",\n";
  o << "  \"removal_rate_m3_per_s\": " << num(r.removal_rate) << ",\n";
  o << "  \"T_peak_K\": " << num(r.T_peak) << ",\n";
  o << "  \"p_peak_Pa\": " << num(r.p_peak) << ",\n";
  o << "  \"wall_time_s\": " << num(wall) << ",\n";
  o << "  \"t_end_s\": " << num(r.t_end) << ",\n";
  o << "  \"S2_center_m\": " << num(r.S2_center) << ",\n";
  o << "  \"melt_thickness_center_m\": " << num(r.g_center) << ",\n";
  o << "  \"volume_vaporized_m3\": " << num(r.volume_vaporized) << ",\n";
  o << "  \"volume_removed_by_flow_m3\": " << num(r.volume_flow) << ",\n";
  o << "  \"volume_melted_m3\": " << num(r.volume_melted) << ",\n";
  o << "  \"u_peak_max_m_per_s\": " << num(r.u_peak_max) << ",\n";
  o << "  \"A_last\": " << num(r.A_last) << ",\n";
  o << "  \"xi_melt_edge\": " << num(r.xi_melt_edge) << ",\n";
  o << "  \"boundary_layer_last_xi\": " << num(r.bl_last_xi) << ",\n";
  o << "  \"steps\": " << r.steps << ",\n";
  o << "  \"nodes\": " << r.nodes << ",\n";
  o << "  \"dt_s\": " << num(cfg.dt) << ",\n";
  o << "  \"dtau\": " << num(r.dtau) << ",\n";
  o << "  \"tau_p\": " << num(r.tau_p) << ",\n";
  o << "  \"max_stable_dt_s\": " << num(r.max_stable_dt) << ",\n";
  o << "  \"melt_thickness_clamps\": " << r.melt_clamps << ",\n";
  o << "  \"melt_rate_clamps\": " << r.melt_rate_clamps << ",\n";
  o << "  \"curvature_clamps\": " << r.curvature_clamps << ",\n";
  o << "  \"b2_limiter_hits\": " << r.b2_clamps << ",\n";
  o << "  \"max_interface_residual\": " << num(r.max_interface_residual) << ",\n";
  o << "  \"case\": {\"intensity_W_per_m2\": " << num(cfg.I0) << ", \"pulse_s\": " << num(cfg.tp)
    << ", \"radius_m\": " << num(cfg.R) << ", \"model\": " << quote(to_string(cfg.model))
    << ", \"m\": " << num(cfg.m) << ", \"xi_p\": " << num(cfg.xi_p) << ", \"Pr\": " << num(cfg.mat.Pr)
    << ", \"solid\": " << quote(to_string(cfg.solid)) << ", \"dxi\": " << num(cfg.dxi)
    << ", \"material\": " << quote(cfg.material) << "},\n";
  const Groups& G = r.groups;
  o << "  \"groups\": {\"Ste\": " << num(G.Ste) << ", \"N_alpha\": " << num(G.Na) << ", \"N_c\": " << num(G.Nc)
    << ", \"k\": " << num(G.k) << ", \"k_prime\": " << num(G.kprime) << ", \"I_prime\": " << num(G.Iprime)
    << ", \"Lambda\": " << num(G.Lambda) << ", \"H_lv\": " << num(G.Hlv) << ", \"N_i\": " << num(G.Ni)
    << ", \"Psi\": " << num(G.Psi) << ", \"theta_i\": " << num(G.theta_i) << ", \"theta_m\": " << num(G.theta_m)
    << ", \"t_scale_s\": " << num(G.t_scale) << "},\n";
  const double sum = e.sum();
  o << "  \"energy_J\": {\"laser_exact\": " << num(e.laser_exact) << ", \"laser_nodal\": " << num(e.laser_nodal)
    << ", \"solid_premelt\": " << num(e.solid_premelt) << ", \"solid_conduction\": " << num(e.solid_conduction)
    << ", \"solid_preheat_moving_origin\": " << num(e.solid_preheat) << ", \"melt_latent\": " << num(e.melt_latent)
    << ", \"vapour_latent\": " << num(e.vapour_latent) << ", \"vapour_kinetic\": " << num(e.vapour_kinetic)
    << ", \"flow_advected\": " << num(e.flow_advected) << ", \"clamp_defect\": " << num(e.clamp_defect)
    << ", \"sum_of_terms\": " << num(sum)
    << ", \"relative_imbalance\": " << num(e.laser_exact > 0 ? (sum - e.laser_exact) / e.laser_exact : 0.0)
    << "}\n";
  o << "}\n";
  return o.str();
}

void write_outputs(const Config& cfg, const Result& r, double wall) {
  namespace fs = std::filesystem;
  fs::create_directories(cfg.out);
  const fs::path dir(cfg.out);
  {
    std::ofstream f(dir / "final_profile.csv");
    f << std::setprecision(10);
    f << "xi,r_m,t_melt_s,S1net_m,S2_m,S1_vaporized_m,g_m,T_surface_K,pressure_Pa,"
         "melting_rate_m_per_s,vaporization_rate_m_per_s,flow_v_m_per_s\n";
    const Frame& fr = r.frames.back();
    for (size_t i = 0; i < r.xi.size(); ++i)
      f << r.xi[i] << "," << r.xi[i] * cfg.R << "," << r.tau_m_s[i] << "," << fr.S1net[i] << ","
        << fr.S2[i] << "," << fr.S1[i] << "," << fr.g[i] << "," << fr.T[i] << "," << fr.p[i] << ","
        << fr.melt_rate[i] << "," << fr.vap_rate[i] << "," << fr.flow_v[i] << "\n";
  }
  {
    std::ofstream f(dir / "centre.csv");
    f << std::setprecision(10);
    f << "t_s,depth_m,S2_m,g_m,T_K,p_Pa,melting_rate_m_per_s,vaporization_rate_m_per_s,A,u_peak_m_per_s,"
         "melting_rate_xi1node,vaporization_rate_xi1node,flow_v_xi1node,"
         "melting_rate_xi_1,vaporization_rate_xi_1,flow_v_xi_1\n";
    for (const auto& c : r.centre)
      f << c.t << "," << c.depth << "," << c.S2 << "," << c.g << "," << c.T << "," << c.p << ","
        << c.melt_rate << "," << c.vap_rate << "," << c.A << "," << c.u_peak << "," << c.melt_rate_1
        << "," << c.vap_rate_1 << "," << c.flow_v_1 << "," << c.melt_rate_x1 << "," << c.vap_rate_x1
        << "," << c.flow_v_x1 << "\n";
  }
  write_h5((dir / "profiles.h5").string(), r);
  // summary last: its presence marks a complete output directory
  std::ofstream f(dir / "summary.json");
  f << summary_json(cfg, r, wall);
  if (!f) throw std::runtime_error("cannot write " + (dir / "summary.json").string());
}

void write_conduction_table(const std::string& dir) {
  namespace fs = std::filesystem;
  std::vector<double> s;
  for (int k = 0; k <= 200; ++k) s.push_back(1e-3 * std::pow(10.0, k / 50.0));  // 1e-3 .. 10
  CorrectedConduction cc(kTau0OverTauM);
  const std::vector<double> ref = reference_gradient(s);
  fs::create_directories(dir);
  std::ofstream f(fs::path(dir) / "conduction_table.csv");
  f << std::setprecision(10);
  // gradients per unit theta_i in x = n / sqrt(N_a tau_m); multiply by theta_i/sqrt(N_a tau_m)
  f << "s,stefan_s1,correction_s2,correction_s3,exact,reference_fd,shifted_1tau0,shifted_3tau0,"
       "shifted_flux_continuous,pre_melting\n";
  for (size_t k = 0; k < s.size(); ++k) {
    const double st = 1.0 / std::sqrt(kPi * (s[k] + kTau0OverTauM));
    // s2 and s3 separately, interpolated in the table
    auto interp = [&](const std::vector<double>& y) {
      const auto& S = cc.s_table();
      size_t j = std::upper_bound(S.begin(), S.end(), s[k]) - S.begin();
      if (j >= S.size()) return y.back();
      const double w = (s[k] - S[j - 1]) / (S[j] - S[j - 1]);
      return (1 - w) * y[j - 1] + w * y[j];
    };
    f << s[k] << "," << st << "," << interp(cc.g2_table()) << "," << interp(cc.g3_table()) << ","
      << cc.gradient(s[k]) << "," << ref[k] << ","
      << 1.0 / std::sqrt(kPi * (s[k] + kTau0OverTauM)) << ","
      << 1.0 / std::sqrt(kPi * (s[k] + 3 * kTau0OverTauM)) << ","
      << 1.0 / std::sqrt(kPi * (s[k] + 4.0 / (kPi * kPi))) << ","
      << 0.5 * std::sqrt(kPi) << "\n";
  }
}

}  // namespace laser
