#pragma once
// A benchmark's job in a child process of its own, so that its peak RSS is its own (not that of
// earlier runs or of the benchmark itself).
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cstdio>
#include <exception>
#include <vector>

namespace objmap::bench {

// Runs `job` in a child process; it writes `n` doubles back through a pipe. False on failure.
template <typename Job>
bool in_child(Job job, double* out, int n, rusage& usage) {
  int fd[2];
  if (pipe(fd) != 0) return false;
  const pid_t pid = fork();
  if (pid < 0) return false;
  if (pid == 0) {
    close(fd[0]);
    int code = 0;
    try {
      std::vector<double> values(n, 0.0);
      job(values.data());
      if (write(fd[1], values.data(), sizeof(double) * n) !=
          static_cast<ssize_t>(sizeof(double) * n))
        code = 1;
    } catch (const std::exception& e) {
      std::fprintf(stderr, "%s\n", e.what());
      code = 1;
    }
    close(fd[1]);
    _exit(code);
  }
  close(fd[1]);
  const ssize_t got = read(fd[0], out, sizeof(double) * n);
  close(fd[0]);
  int status = 0;
  return wait4(pid, &status, 0, &usage) == pid && WIFEXITED(status) && WEXITSTATUS(status) == 0 &&
         got == static_cast<ssize_t>(sizeof(double) * n);
}

}  // namespace objmap::bench
