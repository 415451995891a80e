// pseudohaptic-image-reader: the daemon's image reader (config/image_child.hpp). Enters its sandbox,
// then answers requests on stdin (config/image_wire.hpp) until stdin ends: reads, decodes and resamples
// a region's maps through the image module, or reads an image's size, and writes the answer to stdout.
// Not meant to be run by hand. docs/SERVICE.md, "Images".
#include <sys/prctl.h>
#include <unistd.h>

#include <csignal>

#include <cstdio>
#include <exception>
#include <string>
#include <vector>

#include "config/image_reader.hpp"
#include "config/image_wire.hpp"
#include "config/reader_sandbox.hpp"

#if defined(__SANITIZE_ADDRESS__)
// LeakSanitizer stops the process's threads with ptrace from a process of its own at exit, both of which the sandbox
// forbids: it would end every sanitizer build's reader with "LeakSanitizer has encountered a fatal error" on the
// daemon's standard error. The reader's leaks are looked for in process (fuzz/fuzz_image.cpp, the image tests).
extern "C" int __lsan_is_turned_off() { return 1; }
#endif

int main(int argc, char** argv) {
  if (argc != 1 || ::isatty(0)) {
    std::fprintf(stderr, "%s: pseudohapticd's image reader, started by the daemon; not for use by hand\n", argv[0]);
    return 2;
  }
  // Ends with the daemon's thread that started it: a daemon that stops during a load does not wait for it.
  const pid_t parent = ::getppid();
  ::prctl(PR_SET_PDEATHSIG, SIGKILL);
  if (::getppid() != parent) return 1;  // gone already, before the line above took effect
  for (const std::string& missed : ph::enter_reader_sandbox())
    std::fprintf(stderr, "pseudohaptic-image-reader: sandbox: %s\n", missed.c_str());
  try {
    std::vector<std::byte> bytes;
    while (ph::image_wire::read_message(0, bytes)) ph::image_wire::write_message(1, ph::answer_image_request(bytes));
  } catch (const std::exception& e) {
    std::fprintf(stderr, "pseudohaptic-image-reader: %s\n", e.what());
    return 1;
  }
  return 0;
}
