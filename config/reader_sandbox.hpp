// What the image reader (config/image_reader_main.cpp) gives up before it reads anything: file
// descriptors other than its pipes, capabilities, core dumps, writing files, and through a seccomp filter
// the system calls an image decoder has no use for (sockets, running programs, making processes, writing
// or removing files, signalling other processes, ioctl). Under the service's unit it also inherits the
// unit's own sandbox. docs/SERVICE.md, "Images".
#pragma once

#include <cstdint>
#include <string>
#include <vector>

namespace ph {

// The reader's address space at most (RLIMIT_AS; not under a sanitizer, whose shadow memory needs more): a region's
// fields and their copy for the daemon must fit in it.
inline constexpr std::uint64_t kReaderAddressSpaceBytes = std::uint64_t{8} << 30;

// Applies everything above; returns what could not be applied (for the log), each as one line. The
// seccomp filter failing to install is among them, not an error: the unit's own filter still holds.
std::vector<std::string> enter_reader_sandbox();

}  // namespace ph
