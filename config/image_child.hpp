// Image files read in a short-lived child process: the program pseudohaptic-image-reader, started on the
// first request and ended (stdin closed) when this object goes. It reads, decodes and resamples the
// maps under its own sandbox (config/reader_sandbox.hpp) and hands the fields back over a pipe
// (config/image_wire.hpp). An image that crashes it, or makes it hang or send nonsense, fails that load
// with an error naming the file; the caller keeps whatever it had. docs/SERVICE.md, "Images".
#pragma once

#include <sys/types.h>

#include <chrono>
#include <filesystem>
#include <string>

#include "common/unique_fd.hpp"
#include "config/field_reader.hpp"
#include "config/image_wire.hpp"

namespace ph {

class ImageChild final : public FieldReader {
 public:
  // `reader`: the program; reader_program() by default. A request waits at most `timeout` for its answer.
  explicit ImageChild(std::filesystem::path reader = reader_program(),
                      std::chrono::milliseconds timeout = std::chrono::seconds(120));
  ~ImageChild() override;  // closes the child's stdin and waits for it (kills it if it does not exit)
  ImageChild(const ImageChild&) = delete;
  ImageChild& operator=(const ImageChild&) = delete;

  RegionFields load_fields(const FieldSources& sources, std::int32_t width, std::int32_t height, FieldNeeds needs,
                           FieldLoadReport& report) override;
  ImageSize image_size(const std::filesystem::path& path) override;

  pid_t pid() const { return pid_; }  // -1 before the first request

  // Where the reader program is: PH_IMAGE_READER when set (tests); otherwise beside the image module
  // of the installed program (lib/pseudohaptic/), then where the build tree made it.
  static std::filesystem::path reader_program();

 private:
  image_wire::Answer ask(const image_wire::Request& request, const std::string& files);
  void start();
  void stop();
  [[noreturn]] void fail(const std::string& files, const std::string& what, bool kill_now);

  std::filesystem::path program_;
  std::chrono::milliseconds timeout_;
  pid_t pid_ = -1;
  UniqueFd to_child_, from_child_;
};

}  // namespace ph
