#include "config/reader_sandbox.hpp"

#include <fcntl.h>
#include <linux/audit.h>
#include <linux/filter.h>
#include <linux/seccomp.h>
#include <sched.h>
#include <sys/prctl.h>
#include <sys/resource.h>
#include <sys/syscall.h>
#include <unistd.h>

#include <cerrno>
#include <csignal>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <utility>
#include <vector>

namespace ph {
namespace {

std::string failed(const char* what) { return std::string(what) + ": " + std::strerror(errno); }

#if defined(__x86_64__)
// A classic BPF program over struct seccomp_data: every call is allowed but those listed, which fail
// with EPERM (EACCES for opening a file for writing, ENOSYS for clone3 so that the C library falls back
// to clone, whose flags the filter can see).
class FilterBuilder {
 public:
  void load_nr() { code_.push_back(BPF_STMT(BPF_LD | BPF_W | BPF_ABS, offsetof(seccomp_data, nr))); }
  void load_arg_low(int i) {
    code_.push_back(BPF_STMT(BPF_LD | BPF_W | BPF_ABS, static_cast<__u32>(offsetof(seccomp_data, args) + 8 * i)));
  }
  void load_arg_high(int i) {
    code_.push_back(BPF_STMT(BPF_LD | BPF_W | BPF_ABS, static_cast<__u32>(offsetof(seccomp_data, args) + 8 * i + 4)));
  }
  // if (A == value) return `ret`; A is unchanged otherwise.
  void return_if_equal(__u32 value, __u32 ret) {
    code_.push_back(BPF_JUMP(BPF_JMP | BPF_JEQ | BPF_K, value, 0, 1));
    code_.push_back(BPF_STMT(BPF_RET | BPF_K, ret));
  }
  // if (A & mask) return `ret`.
  void return_if_any_bit(__u32 mask, __u32 ret) {
    code_.push_back(BPF_JUMP(BPF_JMP | BPF_JSET | BPF_K, mask, 0, 1));
    code_.push_back(BPF_STMT(BPF_RET | BPF_K, ret));
  }
  // unless (A & mask) return `ret`.
  void return_unless_any_bit(__u32 mask, __u32 ret) {
    code_.push_back(BPF_JUMP(BPF_JMP | BPF_JSET | BPF_K, mask, 1, 0));
    code_.push_back(BPF_STMT(BPF_RET | BPF_K, ret));
  }
  // if (A != value) return `ret`.
  void return_unless_equal(__u32 value, __u32 ret) {
    code_.push_back(BPF_JUMP(BPF_JMP | BPF_JEQ | BPF_K, value, 1, 0));
    code_.push_back(BPF_STMT(BPF_RET | BPF_K, ret));
  }
  // if (nr == call) { <body>; return ALLOW } else skip it. The body is built by `body` on a fresh builder.
  template <typename Body>
  void on_call(__u32 call, Body body) {
    FilterBuilder inner;
    body(inner);
    inner.code_.push_back(BPF_STMT(BPF_RET | BPF_K, SECCOMP_RET_ALLOW));
    code_.push_back(BPF_JUMP(BPF_JMP | BPF_JEQ | BPF_K, call, 0, static_cast<__u8>(inner.code_.size())));
    code_.insert(code_.end(), inner.code_.begin(), inner.code_.end());
    load_nr();  // the body changed A
  }
  void ret(__u32 value) { code_.push_back(BPF_STMT(BPF_RET | BPF_K, value)); }
  std::vector<sock_filter>& code() { return code_; }

 private:
  std::vector<sock_filter> code_;
};

constexpr __u32 errno_ret(int e) { return SECCOMP_RET_ERRNO | static_cast<__u32>(e); }

std::vector<sock_filter> reader_filter(pid_t self) {
  FilterBuilder f;
  f.code().push_back(BPF_STMT(BPF_LD | BPF_W | BPF_ABS, offsetof(seccomp_data, arch)));
  f.return_unless_equal(AUDIT_ARCH_X86_64, SECCOMP_RET_KILL_PROCESS);
  f.load_nr();
  // The x32 ABI's calls carry this bit: none of them is wanted.
  f.return_if_any_bit(0x40000000U, errno_ret(EPERM));
  const __u32 denied[] = {
      SYS_socket,
      SYS_socketpair,
      SYS_connect,
      SYS_bind,
      SYS_listen,
      SYS_accept,
      SYS_accept4,
      SYS_sendto,
      SYS_sendmsg,
      SYS_sendmmsg,
      SYS_execve,
      SYS_execveat,
      SYS_fork,
      SYS_vfork,
      SYS_ptrace,
      SYS_process_vm_readv,
      SYS_process_vm_writev,
      SYS_kill,
      SYS_tkill,
      SYS_rt_sigqueueinfo,
      SYS_pidfd_open,
      SYS_pidfd_send_signal,
      SYS_ioctl,
      SYS_creat,
      SYS_unlink,
      SYS_unlinkat,
      SYS_rename,
      SYS_renameat,
      SYS_renameat2,
      SYS_mkdir,
      SYS_mkdirat,
      SYS_rmdir,
      SYS_link,
      SYS_linkat,
      SYS_symlink,
      SYS_symlinkat,
      SYS_chmod,
      SYS_fchmod,
      SYS_fchmodat,
      SYS_chown,
      SYS_fchown,
      SYS_lchown,
      SYS_fchownat,
      SYS_truncate,
      SYS_ftruncate,
      SYS_mknod,
      SYS_mknodat,
      SYS_mount,
      SYS_umount2,
      SYS_unshare,
      SYS_setns,
      SYS_chroot,
      SYS_pivot_root,
      SYS_bpf,
      SYS_perf_event_open,
      SYS_keyctl,
      SYS_add_key,
      SYS_request_key,
      SYS_io_uring_setup,
      SYS_userfaultfd,
      SYS_memfd_create,
      SYS_name_to_handle_at,
      SYS_open_by_handle_at,
      SYS_personality,
      SYS_setuid,
      SYS_setgid,
      SYS_setreuid,
      SYS_setregid,
      SYS_setresuid,
      SYS_setresgid,
      SYS_setgroups,
      SYS_setrlimit,
  };
  for (__u32 call : denied) f.return_if_equal(call, errno_ret(EPERM));
  f.return_if_equal(SYS_clone3, errno_ret(ENOSYS));
  // clone: threads only (the decoder may run a pool), no new process.
  f.on_call(SYS_clone, [](FilterBuilder& b) {
    b.load_arg_low(0);
    b.return_unless_any_bit(CLONE_THREAD, errno_ret(EPERM));
  });
  // prlimit64 (what getrlimit is made of): reading a limit only, its new limit NULL, so that an out-of-memory
  // answer can say the limit the reader ran under.
  f.on_call(SYS_prlimit64, [](FilterBuilder& b) {
    b.load_arg_low(2);
    b.return_unless_equal(0, errno_ret(EPERM));
    b.load_arg_high(2);
    b.return_unless_equal(0, errno_ret(EPERM));
  });
  // open and openat: reading only.
  constexpr __u32 writing = O_WRONLY | O_RDWR | O_CREAT | O_TRUNC | O_APPEND;
  f.on_call(SYS_open, [&](FilterBuilder& b) {
    b.load_arg_low(1);
    b.return_if_any_bit(writing, errno_ret(EACCES));
  });
  f.on_call(SYS_openat, [&](FilterBuilder& b) {
    b.load_arg_low(2);
    b.return_if_any_bit(writing, errno_ret(EACCES));
  });
  // tgkill: its own threads only (abort() signals itself so).
  f.on_call(SYS_tgkill, [&](FilterBuilder& b) {
    b.load_arg_low(0);
    b.return_unless_equal(static_cast<__u32>(self), errno_ret(EPERM));
  });
  f.ret(SECCOMP_RET_ALLOW);
  return f.code();
}
#endif

}  // namespace

std::vector<std::string> enter_reader_sandbox() {
  std::vector<std::string> missed;
  // Whatever the spawner left open beyond the pipes and stderr.
  if (::syscall(SYS_close_range, 3U, ~0U, 0U) < 0) missed.push_back(failed("close_range"));
  if (::prctl(PR_SET_NO_NEW_PRIVS, 1, 0, 0, 0) < 0) missed.push_back(failed("no_new_privs"));
  if (::prctl(PR_SET_DUMPABLE, 0, 0, 0, 0) < 0) missed.push_back(failed("not dumpable"));
  if (::prctl(PR_SET_PDEATHSIG, SIGKILL, 0, 0, 0) < 0) missed.push_back(failed("parent death signal"));
  // Capabilities (run as root by hand): none in the bounding set, none held.
  for (int cap = 0; cap <= 63; ++cap) {
    if (::prctl(PR_CAPBSET_READ, cap, 0, 0, 0) == 1) ::prctl(PR_CAPBSET_DROP, cap, 0, 0, 0);
  }
  struct {
    std::uint32_t version, pid;
  } header{0x20080522 /* _LINUX_CAPABILITY_VERSION_3 */, 0};
  struct {
    std::uint32_t effective, permitted, inheritable;
  } data[2]{};
  if (::syscall(SYS_capget, &header, data) == 0 && (data[0].permitted | data[1].permitted) != 0) {
    std::memset(data, 0, sizeof data);
    if (::syscall(SYS_capset, &header, data) < 0) missed.push_back(failed("dropping capabilities"));
  }
  // No core file, a bounded run; memory bounded where no sanitizer maps its shadow. Not RLIMIT_FSIZE:
  // stderr may be a regular file (the daemon's log, run by hand), and a decoder's warning there would
  // kill the reader with SIGXFSZ; the filter below already refuses opening any file for writing.
  const std::pair<int, rlim_t> limits[] = {
    {RLIMIT_CORE, 0},
    {RLIMIT_NOFILE, 64},
    {RLIMIT_CPU, 300},
#if !defined(__SANITIZE_ADDRESS__) && !defined(__SANITIZE_THREAD__)
    {RLIMIT_AS, rlim_t{kReaderAddressSpaceBytes}},
#endif
  };
  for (const auto& [resource, value] : limits) {
    // Never raised: a tighter limit the reader was started under (ulimit, the unit's LimitAS=) stays, and an
    // unprivileged process could not raise it anyway.
    rlimit limit{value, value};
    if (rlimit now{}; ::getrlimit(resource, &now) == 0)  // (RLIM_INFINITY is the largest value)
      limit = {std::min<rlim_t>(value, now.rlim_cur), std::min<rlim_t>(value, now.rlim_max)};
    if (::setrlimit(resource, &limit) < 0) missed.push_back(failed("setrlimit"));
  }
#if defined(__x86_64__)
  std::vector<sock_filter> code = reader_filter(::getpid());
  const sock_fprog program{static_cast<unsigned short>(code.size()), code.data()};
  if (::prctl(PR_SET_SECCOMP, SECCOMP_MODE_FILTER, &program, 0, 0) < 0) missed.push_back(failed("seccomp filter"));
#else
  missed.push_back("seccomp filter: written for x86-64 only");
#endif
  return missed;
}

}  // namespace ph
