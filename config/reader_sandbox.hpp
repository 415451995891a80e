// What the image reader (config/image_reader_main.cpp) gives up before it reads anything: file
// descriptors other than its pipes, capabilities, core dumps, writing files, and through a seccomp filter
// the system calls an image decoder has no use for (sockets, running programs, making processes, writing
// or removing files, signalling other processes, ioctl). Under the service's unit it also inherits the
// unit's own sandbox. docs/SERVICE.md, "Images".
#pragma once

#include <string>
#include <vector>

namespace ph {

// Applies everything above; returns what could not be applied (for the log), each as one line. The
// seccomp filter failing to install is among them, not an error: the unit's own filter still holds.
std::vector<std::string> enter_reader_sandbox();

}  // namespace ph
