// Restart files complete or absent: see restart_guard.h.
#include "restart_guard.h"

#include <mpi.h>

#include <atomic>
#include <cerrno>
#include <csignal>
#include <cstdio>
#include <cstring>
#include <map>
#include <sstream>
#include <thread>

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include "error.h"
#include "input.h"
#include "lammps.h"
#include "output.h"
#include "update.h"
#include "write_restart.h"

using namespace LAMMPS_NS;

namespace {

// Output keeps its restart settings private and Input its command map protected. An explicit
// template instantiation may name a private member (C++17 [temp.explicit]/12); the friend function
// it defines hands out the pointer-to-member (as style_registry.cpp does for Modify's fix map). No
// LIGGGHTS source is patched or copied.
#define MPM_MEMBER(Class, Type, member)                            \
  Type Class::*member_##member();                                  \
  template <Type Class::*M>                                        \
  struct Access_##member {                                         \
    friend Type Class::*member_##member() { return M; }            \
  };                                                               \
  template struct Access_##member<&Class::member>;

MPM_MEMBER(Output, bool, restart_flag)
MPM_MEMBER(Output, bool, restart_flag_single)
MPM_MEMBER(Output, bool, restart_flag_double)
MPM_MEMBER(Output, bigint, next_restart)
MPM_MEMBER(Output, bigint, next_restart_single)
MPM_MEMBER(Output, bigint, next_restart_double)
MPM_MEMBER(Output, bigint, last_restart)
MPM_MEMBER(Output, int, restart_toggle)
MPM_MEMBER(Output, char *, restart1)
MPM_MEMBER(Output, char *, restart2a)
MPM_MEMBER(Output, char *, restart2b)
typedef void (*CommandFn)(LAMMPS *, int, char **);
typedef std::map<std::string, CommandFn> *CommandMap;
MPM_MEMBER(Input, CommandMap, command_map)
#undef MPM_MEMBER

std::string errno_text(const char *what, int err) { return std::string(what) + ": " + std::strerror(err); }

char *new_cstr(const std::string &s) {
  char *c = new char[s.size() + 1];
  std::memcpy(c, s.c_str(), s.size() + 1);
  return c;
}

// Past a file-size limit (ulimit -f) the kernel sends SIGXFSZ, which ends the process by default:
// while a copy runs it is ignored, so that write() returns EFBIG and the copy reports it.
int g_sigxfsz_depth = 0;
struct sigaction g_sigxfsz_saved;

void ignore_sigxfsz() {
  if (g_sigxfsz_depth++ > 0) return;
  struct sigaction ign;
  std::memset(&ign, 0, sizeof ign);
  ign.sa_handler = SIG_IGN;
  sigaction(SIGXFSZ, &ign, &g_sigxfsz_saved);
}

void restore_sigxfsz() {
  if (--g_sigxfsz_depth > 0) return;
  sigaction(SIGXFSZ, &g_sigxfsz_saved, nullptr);
}

// rank 0's message to every rank, then error->all with it if not empty (collective)
void stop_if_failed(LAMMPS *lmp, std::string msg) {
  int me = 0;
  MPI_Comm_rank(lmp->world, &me);
  int n = me == 0 ? static_cast<int>(msg.size()) : 0;
  MPI_Bcast(&n, 1, MPI_INT, 0, lmp->world);
  if (n == 0) return;
  msg.resize(n);
  MPI_Bcast(&msg[0], n, MPI_CHAR, 0, lmp->world);
  lmp->error->all(FLERR, msg.c_str());
}

}  // namespace

namespace mpm {

struct FifoCopy::State {
  std::string fifo, partial;
  std::thread reader;
  std::atomic<bool> done{false};
  long long received = 0;  // bytes read from the FIFO
  bool opened = false;     // a writer opened the FIFO
  std::string error;       // first failure of the copy
};

FifoCopy::FifoCopy(const std::string &file, const std::string &fifo, bool rank0) : file_(file) {
  if (!rank0) return;
  st_.reset(new State);
  State &s = *st_;
  s.fifo = fifo;
  s.partial = file + ".partial";
  ::unlink(fifo.c_str());
  if (::mkfifo(fifo.c_str(), 0600) != 0) {
    s.error = errno_text(("cannot create the FIFO '" + fifo + "'").c_str(), errno);
    s.done = true;
    return;
  }
  ignore_sigxfsz();
  s.reader = std::thread([&s] {
    const int in = ::open(s.fifo.c_str(), O_RDONLY);
    if (in < 0) {
      s.error = errno_text("cannot open the FIFO", errno);
      s.done = true;
      return;
    }
    int out = -1;
    std::vector<char> buf(1 << 20);
    for (;;) {
      const ssize_t n = ::read(in, buf.data(), buf.size());
      if (n < 0 && errno == EINTR) continue;
      if (n < 0) {
        if (s.error.empty()) s.error = errno_text("reading the FIFO", errno);
        break;
      }
      if (n == 0) break;
      if (!s.opened) {
        s.opened = true;
        out = ::open(s.partial.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
        if (out < 0) s.error = errno_text(("cannot open '" + s.partial + "'").c_str(), errno);
      }
      s.received += n;
      // after a failure the rest is read and dropped: the writer must not block on a full FIFO
      for (ssize_t off = 0; out >= 0 && s.error.empty() && off < n;) {
        const ssize_t w = ::write(out, buf.data() + off, static_cast<size_t>(n - off));
        if (w < 0 && errno == EINTR) continue;
        if (w <= 0) {
          std::ostringstream os;
          os << "writing after " << s.received - n + off << " bytes";
          s.error = errno_text(os.str().c_str(), w < 0 ? errno : ENOSPC);
          break;
        }
        off += w;
      }
    }
    ::close(in);
    if (out >= 0) {
      if (s.error.empty() && ::fsync(out) != 0) s.error = errno_text("fsync", errno);
      if (::close(out) != 0 && s.error.empty()) s.error = errno_text("close", errno);
    }
    s.done = true;
  });
}

std::string FifoCopy::finish(bool nothing_is_error) {
  if (!st_) return "";
  State &s = *st_;
  if (s.reader.joinable()) {
    // a reader still waiting for a writer that never came: a writer end opened and closed here
    // lets its open() return (the reader then sees end of file)
    while (!s.done) {
      const int w = ::open(s.fifo.c_str(), O_WRONLY | O_NONBLOCK);
      if (w >= 0) {
        ::close(w);
        break;
      }
      ::usleep(1000);
    }
    s.reader.join();
    restore_sigxfsz();
  }
  ::unlink(s.fifo.c_str());
  std::string err = s.error;
  if (err.empty() && s.opened) {
    struct stat sb;
    if (::stat(s.partial.c_str(), &sb) != 0)
      err = errno_text("stat of the written copy", errno);
    else if (static_cast<long long>(sb.st_size) != s.received) {
      std::ostringstream os;
      os << "the copy holds " << sb.st_size << " of the " << s.received << " bytes written";
      err = os.str();
    } else if (::rename(s.partial.c_str(), file_.c_str()) != 0) {
      err = errno_text("rename into place", errno);
    }
  }
  if (!err.empty() || !s.opened) ::unlink(s.partial.c_str());
  if (err.empty() && !s.opened && nothing_is_error) err = "LIGGGHTS wrote nothing";
  if (err.empty()) return "";
  std::ostringstream os;
  os << "restart file '" << file_ << "' could not be written completely (" << err << ", " << s.received
     << " bytes received); it was not written (an older file of that name is left as it was)";
  return os.str();
}

FifoCopy::~FifoCopy() {
  if (st_ && st_->reader.joinable()) finish(false);
}

void write_restart_checked(LAMMPS *lmp, const std::string &file, const std::function<void(char *)> &write) {
  int me = 0;
  MPI_Comm_rank(lmp->world, &me);
  const std::string fifo = file + ".fifo" + std::to_string(::getpid());
  std::string msg;
  {
    FifoCopy copy(file, fifo, me == 0);
    std::vector<char> path(fifo.begin(), fifo.end());
    path.push_back('\0');
    write(path.data());
    msg = copy.finish(true);
  }
  if (!msg.empty()) msg = "write_restart: " + msg;
  stop_if_failed(lmp, msg);
}

void write_restart_command(LAMMPS *lmp, int narg, char **arg) {
  if (narg < 1 || std::strchr(arg[0], '%')) {
    // one file per process (or no file name: LIGGGHTS' error)
    WriteRestart(lmp).command(narg, arg);
    return;
  }
  std::string file = arg[0];
  const std::size_t star = file.find('*');
  if (star != std::string::npos) file.replace(star, 1, std::to_string(static_cast<long long>(lmp->update->ntimestep)));
  std::vector<char *> args(arg, arg + narg);
  write_restart_checked(lmp, file, [&](char *path) {
    args[0] = path;
    WriteRestart(lmp).command(narg, args.data());
  });
}

void register_restart_command(LAMMPS *lmp) {
  (*(lmp->input->*member_command_map()))["write_restart"] = &write_restart_command;
}

PeriodicRestarts &periodic_restarts() {
  static PeriodicRestarts p;
  return p;
}

void PeriodicRestarts::arm(LAMMPS *lmp) {
  Output *out = lmp->output;
  const bigint step = lmp->update->ntimestep;
  if (step_ >= 0 || !(out->*member_restart_flag()) || out->*member_next_restart() != step ||
      out->*member_last_restart() == step)
    return;
  int me = 0;
  MPI_Comm_rank(lmp->world, &me);
  const std::string pid = std::to_string(::getpid()), n = std::to_string(static_cast<long long>(step));
  char *Output::*names[3] = {member_restart1(), member_restart2a(), member_restart2b()};
  int which[2] = {-1, -1};  // single, double
  if (out->*member_restart_flag_single() && out->*member_next_restart_single() == step) {
    const char *r = out->*names[0];
    if (r && std::strchr(r, '*') && !std::strchr(r, '%')) which[0] = 0;
  }
  if (out->*member_restart_flag_double() && out->*member_next_restart_double() == step) {
    const int k = out->*member_restart_toggle() == 0 ? 1 : 2;
    const char *r = out->*names[k];
    if (r && !std::strchr(r, '%')) which[1] = k;
  }
  for (int k : which) {
    if (k < 0) continue;
    std::string name = out->*names[k], fifo_name;
    if (k == 0) {
      const std::size_t star = name.find('*');
      fifo_name = name + ".fifo" + pid;  // Output replaces the first '*' by the step
      name.replace(star, 1, n);
    } else {
      fifo_name = name + ".fifo" + pid;
    }
    std::string fifo = fifo_name;
    if (k == 0) fifo.replace(fifo.find('*'), 1, n);
    copies_.emplace_back(new FifoCopy(name, fifo, me == 0));
    saved_[k] = out->*names[k];
    ours_[k] = new_cstr(fifo_name);
    out->*names[k] = ours_[k];
  }
  if (!copies_.empty()) {
    step_ = step;
    lmp_ = lmp;
  }
}

void PeriodicRestarts::restore() {
  if (!lmp_) return;
  char *Output::*names[3] = {member_restart1(), member_restart2a(), member_restart2b()};
  for (int k = 0; k < 3; ++k) {
    if (!ours_[k]) continue;
    if (lmp_->output->*names[k] == ours_[k]) {
      lmp_->output->*names[k] = saved_[k];
      delete[] ours_[k];
    }
    ours_[k] = saved_[k] = nullptr;
  }
}

void PeriodicRestarts::settle(LAMMPS *lmp) {
  if (step_ < 0) return;
  restore();
  std::string msg;
  for (auto &c : copies_) {
    const std::string m = c->finish(false);
    if (msg.empty() && !m.empty()) msg = "restart: " + m;
  }
  copies_.clear();
  step_ = -1;
  lmp_ = nullptr;
  stop_if_failed(lmp, msg);
}

PeriodicRestarts::~PeriodicRestarts() {
  copies_.clear();
}

}  // namespace mpm
