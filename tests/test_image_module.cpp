// The image module (config/image_backend.hpp): OpenImageIO is mapped only once an image is read or written,
// a scene without images never maps it, errors thrown inside the module reach the program as FieldError,
// and a module that cannot be loaded gives a FieldError that says what was tried.
//
// Loading is once per process, so every check runs in a child of its own (fork) and this process never
// touches an image: each test sees a process in which nothing has loaded the module yet, whatever ran before.
#include <sys/wait.h>
#include <unistd.h>

#include <gtest/gtest.h>

#include <cerrno>
#include <cstdlib>
#include <exception>
#include <filesystem>
#include <fstream>
#include <functional>
#include <iterator>
#include <string>
#include <typeinfo>

#include "config/image_io.hpp"
#include "config/scene_file.hpp"
#include "core/engine/default_scene.hpp"
#include "tests/scratch_dir.hpp"

namespace ph {
namespace {

namespace fs = std::filesystem;

// Runs body in a child process; returns what it returned (empty: passed), or why the child failed.
std::string in_child(const std::function<std::string()>& body) {
  int fds[2];
  if (::pipe(fds) != 0) return "pipe failed";
  const pid_t pid = ::fork();
  if (pid < 0) return "fork failed";
  if (pid == 0) {
    ::close(fds[0]);
    std::string failure;
    try {
      failure = body();
    } catch (const std::exception& e) {
      failure = std::string("unexpected exception ") + typeid(e).name() + ": " + e.what();
    } catch (...) {
      failure = "unexpected exception of unknown type";
    }
    std::size_t done = 0;
    while (done < failure.size()) {
      const ssize_t n = ::write(fds[1], failure.data() + done, failure.size() - done);
      if (n <= 0) break;
      done += static_cast<std::size_t>(n);
    }
    ::_exit(failure.empty() ? 0 : 1);
  }
  ::close(fds[1]);
  std::string message;
  char buffer[512];
  for (;;) {
    const ssize_t n = ::read(fds[0], buffer, sizeof buffer);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) break;
    message.append(buffer, static_cast<std::size_t>(n));
  }
  ::close(fds[0]);
  int status = 0;
  while (::waitpid(pid, &status, 0) < 0 && errno == EINTR) {
  }
  if (!WIFEXITED(status)) return "child did not exit normally (status " + std::to_string(status) + ") " + message;
  if (WEXITSTATUS(status) != 0 && message.empty()) return "child exited " + std::to_string(WEXITSTATUS(status));
  return message;
}

// Whether a library whose file name contains `name` is mapped into this process.
bool mapped(const std::string& name) {
  std::ifstream maps("/proc/self/maps");
  const std::string text{std::istreambuf_iterator<char>(maps), std::istreambuf_iterator<char>()};
  return text.find(name) != std::string::npos;
}

std::string oiio_mapped_state(bool expected, const std::string& when) {
  for (const char* name : {"libOpenImageIO", "ph_image_oiio"}) {
    if (mapped(name) != expected)
      return std::string(name) + (expected ? " is not mapped " : " is mapped ") + when + "\n";
  }
  return {};
}

TEST(ImageModule, OpenImageIOIsMappedOnlyOnceAnImageIsUsed) {
  const ScratchDir dir("image-module");
  const std::string failure = in_child([&]() -> std::string {
    if (std::string f = oiio_mapped_state(false, "at start"); !f.empty()) return f;
    const SceneSpec flat = parse_scene_text("[daemon]\ndesktop = [0, 0, 1920, 1080]\n", dir.path() / "flat.toml");
    const Scene scene = load_scene(flat);
    const Scene built_in = default_scene();
    if (!scene.regions().empty() || built_in.regions().empty()) return "unexpected scenes";
    if (std::string f = oiio_mapped_state(false, "after loading a flat scene and the default scene"); !f.empty())
      return f;
    Grid<float> values(4, 3);
    values.at(1, 1) = 0.5f;
    write_gray_png16(dir / "gray.png", values);
    if (std::string f = oiio_mapped_state(true, "after writing an image"); !f.empty()) return f;
    const RawImage image = read_image(dir / "gray.png");
    if (image.width != 4 || image.height != 3 || image.channels != 1) return "read back the wrong size";
    return {};
  });
  EXPECT_EQ(failure, "");
}

TEST(ImageModule, ReadingAnImageSizeLoadsIt) {
  const ScratchDir dir("image-module");
  const std::string failure = in_child([&]() -> std::string {
    if (std::string f = oiio_mapped_state(false, "at start"); !f.empty()) return f;
    const std::string missing = (dir / "missing.tif").string();  // a PNG's size is read without the module
    try {
      read_image_size(missing);
      return "no error for a missing file";
    } catch (const FieldError& e) {
      if (std::string(e.what()).rfind(missing + ": ", 0) != 0) return std::string("message: ") + e.what();
    }
    return oiio_mapped_state(true, "after reading an image size");
  });
  EXPECT_EQ(failure, "");
}

// A PNG map (the normal and depth maps the project's tools write) is read with libpng: OpenImageIO stays unmapped,
// and a module that could not be loaded does not matter.
TEST(ImageModule, ReadingAPngDoesNotLoadIt) {
  const std::string failure = in_child([&]() -> std::string {
    ::setenv("PH_IMAGE_MODULE", "/nonexistent/ph_image_oiio.so", 1);
    const fs::path seeds = PH_IMAGE_SEEDS_DIR;
    const RawImage depth = read_image(seeds / "depth16.png");
    const RawImage normals = read_image(seeds / "normal16.png");
    const ImageSize size = read_image_size(seeds / "depth8.png");
    if (depth.channels != 1 || normals.channels != 3 || depth.code_max != 65535 || size.code_max != 255 ||
        size.width != depth.width)
      return "read back the wrong image";
    return oiio_mapped_state(false, "after reading PNG files");
  });
  EXPECT_EQ(failure, "");
}

// FieldError is thrown inside the module (its own copy of the type's typeinfo, hidden there) and caught here
// by type: libstdc++ matches exception types by their names.
TEST(ImageModule, ErrorsFromTheModuleAreCaughtAsFieldError) {
  const ScratchDir dir("image-module");
  std::ofstream(dir / "truncated.tif", std::ios::binary) << "II*\0\x08\0\0\0\x0e\0";  // TIFF: the module reads it
  const std::string failure = in_child([&]() -> std::string {
    std::string failures;
    const auto expect_field_error = [&](const char* what, const std::function<void()>& action) {
      try {
        action();
        failures += std::string(what) + ": no exception\n";
      } catch (const FieldError& e) {
        if (std::string(e.what()).find(dir.path().string()) == std::string::npos)
          failures += std::string(what) + ": message does not name the file: " + e.what() + "\n";
      } catch (const std::exception& e) {
        failures += std::string(what) + ": caught as " + typeid(e).name() + ", not FieldError: " + e.what() + "\n";
      }
    };
    expect_field_error("missing file", [&] { read_image(dir / "missing.tif"); });
    expect_field_error("truncated file", [&] { read_image(dir / "truncated.tif"); });
    expect_field_error("unwritable path", [&] { write_float_exr(dir / "no-such-dir" / "x.exr", Grid<float>(2, 2)); });
    if (!mapped("ph_image_oiio")) failures += "the module was not loaded\n";
    return failures;
  });
  EXPECT_EQ(failure, "");
}

TEST(ImageModule, AModuleThatCannotBeLoadedIsAFieldErrorThatSaysWhatWasTried) {
  const ScratchDir dir("image-module");
  const fs::path module = dir / "no-such-module.so";
  const fs::path image = dir / "image.tif";  // not a PNG: those are read without the module
  const std::string failure = in_child([&]() -> std::string {
    ::setenv("PH_IMAGE_MODULE", module.c_str(), 1);
    std::string failures;
    for (int attempt = 0; attempt < 2; ++attempt) {  // a failed load is not cached: the second says it again
      try {
        read_image(image);
        return "no error";
      } catch (const FieldError& e) {
        const std::string message = e.what();
        if (message.rfind(image.string() + ": ", 0) != 0) failures += "does not start with the image: " + message;
        if (message.find("image module") == std::string::npos) failures += "does not name the module: " + message;
        if (message.find(module.string() + ": ") == std::string::npos)
          failures += "does not name the path tried: " + message;
        if (message.find("PH_IMAGE_MODULE") == std::string::npos) failures += "does not say where from: " + message;
        if (message.find("No such file") == std::string::npos) failures += "has no dlerror(): " + message;
      }
    }
    if (mapped("libOpenImageIO")) failures += "OpenImageIO is mapped\n";
    return failures;
  });
  EXPECT_EQ(failure, "");
}

}  // namespace
}  // namespace ph
