// fix balance/mpm: static load balance along one or more dimensions for
// LIGGGHTS 3.8, which has no 'balance' command. Places the cuts between the
// subdomains of each listed processor-grid dimension so that every slab along
// it holds the same weight of atoms (material points of fix mpm/fluid, grains,
// ...; the weight summed over the other dimensions), moves the atoms to their
// new owners and lets LIGGGHTS rebuild its communication and bins.
// User page: docs/fix_balance_mpm.md.
#ifdef FIX_CLASS
FixStyle(balance/mpm,FixBalanceMpm)
#else

#ifndef LMP_FIX_BALANCE_MPM_H
#define LMP_FIX_BALANCE_MPM_H

#include <string>
#include <vector>

#include "fix.h"

namespace LAMMPS_NS {

class FixBalanceMpm : public Fix {
 public:
  FixBalanceMpm(class LAMMPS *, int, char **);
  int setmask() override;
  void init() override;
  void setup_pre_exchange() override;
  int modify_param(int, char **) override;
  void pre_exchange() override;
  double compute_vector(int) override;

 private:
  int parse_dims(int narg, char **arg, int iarg);  // keyword dim's values from arg[iarg]; next iarg
  void bad_arg(const char *keyword, const char *expected, const char *given);
  void check_weights();                     // the total weight stays finite (collective)
  double weight(int i) const;              // the atom's weight (times the rank's scale, measured)
  double base_weight(int i) const;         // the atom's weight from its groups
  std::vector<class FixMpmFluid *> fluid_fixes() const;
  void measure();                          // measured: scale_ and the measured imbalance (collective)
  // of the weights on the rank grid of these cuts (one list per dims_ entry; collective)
  double grid_imbalance(const std::vector<std::vector<double>> &cuts) const;
  double volume_below(int dim, double c) const;  // weight of the box volume below c along dim
  double box_volume_weight(const double *lo, const double *hi) const;  // of the box lo..hi (keyword volume)
  double imbalance() const;                 // max rank weight / mean rank weight (collective)
  void find_cuts(int dim, std::vector<double> &cut);  // new cut coordinates along dim (collective)
  int max_slabs() const;                    // the largest processor count of the listed dims
  void apply_cuts(const std::vector<std::vector<double>> &cuts);  // splits, atoms, comm, bins
  void print_line() const;                  // the balance's line on screen and in the log
  void balance();

  std::vector<int> dims_;  // the listed dims (0, 1, 2), distinct, in the order given
  int every_ = 0;        // 0: only at the setup of each run
  double thresh_ = 1.0;  // balance only if the imbalance exceeds this
  std::vector<int> wgroup_bits_;
  std::vector<double> wvalues_;
  double wvol_ = 0.0;    // weight per unit volume of the box (keyword volume)
  std::vector<std::vector<double>> cut_;  // current cuts (absolute) per listed dim, procgrid[dim]+1 values
  double imb_before_ = 1.0, imb_after_ = 1.0;
  int nbalance_ = 0;
  bool measured_ = false;    // keyword measured: weights scaled by each rank's measured work
  bool have_busy_ = false, scaled_ = false;
  double busy_last_ = 0.0;   // fix mpm/fluid's work on this rank at the last balance (s)
  double scale_ = 1.0;       // this rank's work per unit weight over the mean (measured)
};

}  // namespace LAMMPS_NS

#endif
#endif
