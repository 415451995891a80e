// The daemon's image reader child: the fields it hands back equal those read in process, the process
// that asks never maps the image module, and a corrupt image, a crashing or lying reader is an error that
// names the file, never a crash of the asking process. Also the reader's sandbox itself.
#include <fcntl.h>
#include <gtest/gtest.h>
#include <sys/resource.h>
#include <sys/socket.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <cmath>
#include <fstream>
#include <functional>
#include <optional>
#include <string>
#include <thread>

#include "config/image_child.hpp"
#include "config/image_reader.hpp"
#include "config/image_wire.hpp"
#include "config/reader_sandbox.hpp"
#include "config/scene_file.hpp"
#include "config/target_files.hpp"
#include "core/engine/targets.hpp"
#include "tests/file_bytes.hpp"
#include "tests/scratch_dir.hpp"
#include "tests/thrown_message.hpp"

namespace ph {
namespace {

void write_text(const std::filesystem::path& path, const std::string& text) {
  std::ofstream(path, std::ios::binary) << text;
}

// Runs `body` in a forked child and returns its exit status: what writes images maps the image module,
// which this process must not.
template <typename Body>
int in_child(Body body) {
  const pid_t pid = ::fork();
  if (pid == 0) _exit(body());
  int status = 0;
  ::waitpid(pid, &status, 0);
  return WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
}

bool maps_image_library() {
  const std::string maps = read_file_text("/proc/self/maps");
  return maps.find("ph_image_oiio") != std::string::npos || maps.find("OpenImageIO") != std::string::npos;
}

// 160 rows: on a machine of two cores or more the reader decodes the map and makes the class maps in two bands of
// rows, one on a thread of its own in its sandbox.
TargetSpec small_target() {
  TargetSpec spec = all_targets().front();
  spec.size = 160;
  return spec;
}

// A scene with one region of `spec`, with materials so that the image size is asked for too.
std::filesystem::path write_scene(const std::filesystem::path& dir, const TargetSpec& spec) {
  EXPECT_EQ(in_child([&] {
              write_target_files(dir, {spec});
              return 0;
            }),
            0);
  const std::filesystem::path scene = target_file_paths(dir, spec).scene;
  write_text(scene, read_file_text(scene) + "\n[region.materials]\nsource = \"depth\"\n");
  return scene;
}

TEST(ImageChild, FieldsEqualThoseReadInProcessAndTheModuleIsNeverMappedHere) {
  const ScratchDir dir("image-child");
  const TargetSpec spec = small_target();
  const std::filesystem::path scene_file = write_scene(dir.path(), spec);
  ASSERT_FALSE(maps_image_library());
  const SceneSpec spec_file = parse_scene_file(scene_file);
  pid_t reader_pid = -1;
  Scene from_child;
  {
    ImageChild child;
    from_child = load_scene(spec_file, nullptr, &child);
    reader_pid = child.pid();
  }
  EXPECT_GT(reader_pid, 0);
  EXPECT_FALSE(maps_image_library()) << "the image module was mapped by the asking process";
  EXPECT_EQ(::kill(reader_pid, 0), -1) << "the reader still runs after the load";
  const Scene here = load_scene(spec_file);
  ASSERT_EQ(from_child.regions().size(), 1u);
  const RegionFields& a = from_child.regions()[0].fields;
  const RegionFields& b = here.regions()[0].fields;
  ASSERT_TRUE(a.gradient && b.gradient);
  ASSERT_EQ(a.gradient->values.size(), b.gradient->values.size());
  for (std::size_t i = 0; i < a.gradient->values.size(); ++i) {
    ASSERT_EQ(a.gradient->values[i].x, b.gradient->values[i].x) << i;
    ASSERT_EQ(a.gradient->values[i].y, b.gradient->values[i].y) << i;
  }
  EXPECT_EQ(from_child.regions()[0].effects.size(), here.regions()[0].effects.size());
}

// A hybrid region loaded through the reader is prepared as in process: its depth map, which the method reads where
// one is given (FieldNeeds::depth_if_given; until 2026-11-26 it did not cross, and the daemon's hybrid regions had
// none), and the rounding its maps' storage leaves (the smoothing band) cross with the fields, so the heights, the
// smoothed normals and the marks are the same, bit for bit.
TEST(ImageChild, AHybridRegionIsPreparedAsInProcess) {
  const ScratchDir dir("image-child-hybrid");
  const std::filesystem::path scene_file = write_scene(dir.path(), small_target());
  std::string text = read_file_text(scene_file);
  const std::string curvature = "method = \"curvature\"";
  ASSERT_NE(text.find(curvature), std::string::npos) << text;
  text.replace(text.find(curvature), curvature.size(), "method = \"hybrid\"");
  write_text(scene_file, text);
  const SceneSpec spec = parse_scene_file(scene_file);
  Scene from_child;
  {
    ImageChild child;
    from_child = load_scene(spec, nullptr, &child);
  }
  const Scene here = load_scene(spec);
  const RegionFields& a = from_child.regions().at(0).fields;
  const RegionFields& b = here.regions().at(0).fields;
  EXPECT_GT(b.gradient_rounding, 0.0);  // the targets' 16-bit normal map
  EXPECT_EQ(a.gradient_rounding, b.gradient_rounding);
  EXPECT_GT(b.depth_rounding, 0.0);  // and its 16-bit depth map
  EXPECT_EQ(a.depth_rounding, b.depth_rounding);
  ASSERT_TRUE(a.gradient && b.gradient && a.discontinuity && b.discontinuity);
  ASSERT_TRUE(b.depth);
  ASSERT_TRUE(a.depth);
  for (std::size_t i = 0; i < a.gradient->values.size(); ++i) {
    ASSERT_EQ(a.gradient->values[i].x, b.gradient->values[i].x) << i;
    ASSERT_EQ(a.gradient->values[i].y, b.gradient->values[i].y) << i;
    ASSERT_EQ(a.depth->values[i], b.depth->values[i]) << i;
    ASSERT_EQ(a.discontinuity->values[i], b.discontinuity->values[i]) << i;
  }
  // (Read from the heights and normals in each process: the same figures, and not both empty.)
  ASSERT_TRUE(b.slope_comparison && b.slope_comparison->ratio && b.slope_comparison->depth_flat);
  EXPECT_EQ(a.slope_comparison, b.slope_comparison);
}

// PNG, TIFF and OpenEXR, 8-bit, 16-bit and float, as normal and depth maps: the sandboxed reader reads
// each as this process would (the sandbox leaves every decoder what it needs).
TEST(ImageChild, ReadsEveryFormatInItsSandboxAsInProcess) {
  ImageChild child;
  int files = 0;
  for (const auto& entry : std::filesystem::directory_iterator(PH_IMAGE_SEEDS_DIR)) {
    const std::filesystem::path path = entry.path();
    FieldSources sources;
    FieldNeeds needs{true, false};
    if (path.filename().string().rfind("normal", 0) == 0) {
      sources.normal_map = path;
    } else {
      sources.depth_map = path;
      needs.depth = true;
    }
    FieldLoadReport from_child_report, here_report;
    const RegionFields a = child.load_fields(sources, 16, 12, needs, from_child_report);
    const RegionFields b = load_region_fields(sources, 16, 12, needs, here_report);
    ASSERT_TRUE(a.gradient && b.gradient) << path;
    EXPECT_EQ(a.gradient->values.size(), 16u * 12u) << path;
    for (std::size_t i = 0; i < a.gradient->values.size(); ++i) {
      ASSERT_EQ(a.gradient->values[i].x, b.gradient->values[i].x) << path << " texel " << i;
      ASSERT_EQ(a.gradient->values[i].y, b.gradient->values[i].y) << path << " texel " << i;
    }
    EXPECT_EQ(a.gradient_rounding, b.gradient_rounding) << path;  // the hybrid method's smoothing band reads it
    EXPECT_EQ(a.depth_rounding, b.depth_rounding) << path;        // and its reading of normals from the heights
    EXPECT_EQ(from_child_report.normals.value_step, here_report.normals.value_step) << path;
    EXPECT_EQ(child.image_size(path).code_max, read_image_size(path).code_max) << path;
    ++files;
  }
  EXPECT_GE(files, 6);
}

TEST(ImageChild, CorruptImagesAreErrorsThatNameTheFile) {
  const ScratchDir dir("image-child-corrupt");
  const std::filesystem::path scene_file = write_scene(dir.path(), small_target());
  const SceneSpec spec = parse_scene_file(scene_file);
  const std::filesystem::path depth = *spec.regions[0].sources.depth_map;
  const std::string png = read_file_text(depth);
  for (const std::string& bad : {png.substr(0, png.size() / 2), png.substr(0, 40) + std::string(4000, '\x5a'),
                                 std::string("\x89PNG\r\n\x1a\n") + std::string(300, '\xff')}) {
    write_text(depth, bad);
    ImageChild child;
    const std::string message = thrown_message<ConfigError>([&] { load_scene(spec, nullptr, &child); });
    EXPECT_NE(message.find(depth.string()), std::string::npos) << message;
  }
}

// A stand-in for the reader program: a shell script.
std::filesystem::path fake_reader(const std::filesystem::path& dir, const std::string& body) {
  const std::filesystem::path path = dir / "fake-reader";
  write_text(path, "#!/bin/sh\n" + body + "\n");
  ::chmod(path.c_str(), 0755);
  return path;
}

FieldSources depth_only(const std::filesystem::path& path) {
  FieldSources sources;
  sources.depth_map = path;
  return sources;
}

TEST(ImageChild, AReaderThatCrashesFailsTheRequestNamingTheFile) {
  const ScratchDir dir("image-child-crash");
  ImageChild child(fake_reader(dir.path(), "kill -SEGV $$"));
  FieldLoadReport report;
  const std::string message = thrown_message<FieldError>([&] {
    child.load_fields(depth_only("/x/map.png"), 8, 8, {false, true}, report);
  });
  EXPECT_NE(message.find("/x/map.png"), std::string::npos) << message;
  EXPECT_NE(message.find("killed by signal 11 (SIGSEGV)"), std::string::npos) << message;
  // The next request starts a new reader (which crashes again, and says so again).
  EXPECT_NE(thrown_message<FieldError>([&] { child.image_size("/x/other.png"); }).find("/x/other.png"),
            std::string::npos);
}

TEST(ImageChild, AReaderThatSendsNonsenseFailsTheRequest) {
  const ScratchDir dir("image-child-lies");
  // A message of 16 bytes that claims to be a fields answer and is cut short.
  ImageChild child(fake_reader(dir.path(), "printf '\\020\\0\\0\\0\\0\\0\\0\\0\\003abcdefghijklmno'; sleep 5"));
  FieldLoadReport report;
  const std::string message = thrown_message<FieldError>([&] {
    child.load_fields(depth_only("/x/map.png"), 8, 8, {false, true}, report);
  });
  EXPECT_NE(message.find("sent a wrong answer"), std::string::npos) << message;
}

TEST(ImageChild, AReaderThatHangsIsKilledAfterTheTimeout) {
  const ScratchDir dir("image-child-hang");
  ImageChild child(fake_reader(dir.path(), "exec sleep 60"), std::chrono::milliseconds(300));
  const auto start = std::chrono::steady_clock::now();
  const std::string message = thrown_message<FieldError>([&] { child.image_size("/x/slow.png"); });
  EXPECT_LT(std::chrono::steady_clock::now() - start, std::chrono::seconds(10));
  EXPECT_NE(message.find("no answer within"), std::string::npos) << message;
}

TEST(ImageChild, AReaderThatStopsInTheMiddleOfAnAnswerIsKilledAfterTheTimeout) {
  const ScratchDir dir("image-child-half");
  ImageChild child(fake_reader(dir.path(), "printf '\\020\\0\\0\\0\\0\\0\\0\\0\\003abc'; exec sleep 60"),
                   std::chrono::milliseconds(300));
  const auto start = std::chrono::steady_clock::now();
  const std::string message = thrown_message<FieldError>([&] { child.image_size("/x/half.png"); });
  EXPECT_LT(std::chrono::steady_clock::now() - start, std::chrono::seconds(10));
  EXPECT_NE(message.find("not complete in time"), std::string::npos) << message;
}

// Runs `check` in a child process whose address space is limited to what it uses now plus `headroom` (the reader's
// own limit is 8 GiB, more than a test should take), after `before` ran there unlimited; its one-letter verdict.
// (Unused under a sanitizer, where the test that calls it is skipped.)
[[maybe_unused]] char under_memory_limit(std::size_t headroom, const std::function<void()>& before,
                                         const std::function<char()>& check) {
  int ends[2];
  if (::pipe(ends) != 0) return 'p';
  const pid_t child = ::fork();
  if (child < 0) return 'f';
  if (child == 0) {
    ::close(ends[0]);
    char verdict = 'l';
    try {
      before();
      std::ifstream status("/proc/self/status");
      std::size_t vm_kib = 0;
      for (std::string key; status >> key;) {
        if (key == "VmSize:") {
          status >> vm_kib;
          break;
        }
      }
      const rlim_t limit = static_cast<rlim_t>(vm_kib) * 1024 + headroom;
      const rlimit rl{limit, limit};
      if (vm_kib > 0 && ::setrlimit(RLIMIT_AS, &rl) == 0) verdict = check();
    } catch (...) {
      verdict = 'x';
    }
    (void)!::write(ends[1], &verdict, 1);
    ::_exit(0);
  }
  ::close(ends[1]);
  char verdict = '?';
  (void)!::read(ends[0], &verdict, 1);
  ::close(ends[0]);
  ::waitpid(child, nullptr, 0);
  return verdict;
}

// 'y' when `answer` is a Failure that says the reader ran out of memory.
[[maybe_unused]] char out_of_memory_verdict(const image_wire::Answer& answer) {
  const auto* failure = std::get_if<image_wire::Failure>(&answer);
  if (failure == nullptr) return 'a';
  return failure->message.find("not enough memory to read it") != std::string::npos ? 'y' : 'm';
}

// A region too large for the reader's memory is said as such, as an answer, whether the reading runs out (the fields)
// or the answer's copy for the wire does: the reader used to end on std::bad_alloc there, and the daemon could only
// say that it "ended without an answer".
TEST(ImageChild, ARegionTooLargeForTheReadersMemoryIsSaidAsSuch) {
#if defined(__SANITIZE_ADDRESS__) || defined(__SANITIZE_THREAD__)
  GTEST_SKIP() << "a sanitizer's shadow memory needs more address space than the limit this test sets";
#else
  const ScratchDir dir("image-child-memory");
  const TargetSpec spec = small_target();
  const SceneSpec scene = parse_scene_file(write_scene(dir.path(), spec));
  image_wire::FieldsRequest request;
  request.sources = scene.regions.at(0).sources;
  request.width = request.height = kMaxRegionSide;  // 16384^2: 2 GiB of slopes, 1 GiB of heights
  request.needs = {.gradient = true, .depth = true};
  const std::vector<std::byte> asked = image_wire::encode(image_wire::Request{request});
  const char reading = under_memory_limit(
      std::size_t{256} << 20, [] {},
      [&] {
        return out_of_memory_verdict(
            image_wire::decode_answer(answer_image_request(asked), image_wire::Request{request}));
      });
  EXPECT_EQ(reading, 'y') << "l: no limit; x: threw; a: answered with fields; m: another failure";

  // An answer of 512 MiB of slopes made before the limit, which leaves no room for its copy for the wire.
  image_wire::FieldsRequest slopes;
  slopes.width = slopes.height = 8192;
  slopes.needs = {.gradient = true};
  std::optional<image_wire::Answer> answer;
  const char encoding = under_memory_limit(
      std::size_t{256} << 20,
      [&] {
        image_wire::FieldsAnswer made;
        made.fields.gradient.emplace(8192, 8192);
        answer.emplace(std::move(made));
      },
      [&] {
        return out_of_memory_verdict(image_wire::decode_answer(encode_answer(*answer), image_wire::Request{slopes}));
      });
  EXPECT_EQ(encoding, 'y') << "l: no limit; x: threw; a: answered with fields; m: another failure";
#endif
}

TEST(ImageWire, RequestsCarryEveryNeed) {
  for (const FieldNeeds needs : {FieldNeeds{true, false, false}, FieldNeeds{false, true, false},
                                 FieldNeeds{true, false, true}, FieldNeeds{true, true, true}}) {
    image_wire::FieldsRequest request;
    request.sources.depth_map = "/x/depth.png";
    request.width = 3;
    request.height = 2;
    request.needs = needs;
    const auto back = std::get<image_wire::FieldsRequest>(image_wire::decode_request(image_wire::encode(request)));
    EXPECT_EQ(back.needs.gradient, needs.gradient);
    EXPECT_EQ(back.needs.depth, needs.depth);
    EXPECT_EQ(back.needs.depth_if_given, needs.depth_if_given);
    // A method that reads the heights where they are given gets them from a region with a depth map: an answer
    // without them is refused, as one with them where none were asked for.
    image_wire::FieldsAnswer with_depth, without;
    if (needs.gradient) with_depth.fields.gradient = without.fields.gradient = GradientField(3, 2);
    with_depth.fields.depth = DepthField(3, 2);
    const bool depth_asked = needs.depth || needs.depth_if_given;
    const image_wire::FieldsAnswer& right = depth_asked ? with_depth : without;
    const image_wire::FieldsAnswer& wrong = depth_asked ? without : with_depth;
    EXPECT_TRUE(std::holds_alternative<image_wire::FieldsAnswer>(
        image_wire::decode_answer(image_wire::encode(image_wire::Answer{right}), back)));
    EXPECT_THROW(image_wire::decode_answer(image_wire::encode(image_wire::Answer{wrong}), back), image_wire::WireError);
  }
}

TEST(ImageWire, AnswersWithNonFiniteOrMisshapenFieldsAreRefused) {
  image_wire::FieldsRequest request;
  request.width = 2;
  request.height = 1;
  request.needs = {true, false};
  image_wire::FieldsAnswer answer;
  answer.fields.gradient = GradientField(2, 1, Gradient{0.5f, -0.5f});
  const auto ok = image_wire::decode_answer(image_wire::encode(image_wire::Answer{answer}), request);
  ASSERT_TRUE(std::holds_alternative<image_wire::FieldsAnswer>(ok));
  EXPECT_EQ(std::get<image_wire::FieldsAnswer>(ok).fields.gradient->values[1].y, -0.5f);

  answer.fields.gradient->values[1].x = std::nanf("");
  EXPECT_THROW(image_wire::decode_answer(image_wire::encode(image_wire::Answer{answer}), request),
               image_wire::WireError);
  answer.fields.gradient = GradientField(1, 2);  // the right count, the wrong shape
  EXPECT_THROW(image_wire::decode_answer(image_wire::encode(image_wire::Answer{answer}), request),
               image_wire::WireError);
  answer.fields.gradient = GradientField(2, 1);
  answer.fields.depth = DepthField(2, 1);  // a field not asked for
  EXPECT_THROW(image_wire::decode_answer(image_wire::encode(image_wire::Answer{answer}), request),
               image_wire::WireError);
  answer.fields.depth.reset();
  answer.fields.gradient_rounding = 0.0023;  // an 8-bit map's: crosses as it is
  answer.fields.depth_rounding = 0.11;       // a 16-bit depth map's of 100 px relief, the same
  const auto rounded = image_wire::decode_answer(image_wire::encode(image_wire::Answer{answer}), request);
  EXPECT_EQ(std::get<image_wire::FieldsAnswer>(rounded).fields.gradient_rounding, 0.0023);
  EXPECT_EQ(std::get<image_wire::FieldsAnswer>(rounded).fields.depth_rounding, 0.11);
  for (double* sigma : {&answer.fields.gradient_rounding, &answer.fields.depth_rounding}) {
    const double good = *sigma;
    for (double bad : {std::nan(""), -1e-3, std::numeric_limits<double>::infinity()}) {
      *sigma = bad;
      EXPECT_THROW(image_wire::decode_answer(image_wire::encode(image_wire::Answer{answer}), request),
                   image_wire::WireError)
          << bad;
    }
    *sigma = good;
  }
}

// The reader's limits never raise one it was started under, soft or hard (a user's `ulimit -S`, a unit's LimitCPU=).
TEST(ReaderSandbox, NeverRaisesALimitItWasStartedUnder) {
  const int status = in_child([] {
    const rlimit soft{10, RLIM_INFINITY};  // 10 s of CPU, soft only
    if (::setrlimit(RLIMIT_CPU, &soft) != 0) return 1;
    enter_reader_sandbox();
    rlimit now{};
    if (::getrlimit(RLIMIT_CPU, &now) != 0) return 2;
    return now.rlim_cur == 10 && now.rlim_max == 300 ? 0 : 3;  // the soft limit kept; the hard one the reader's
  });
  EXPECT_EQ(status, 0) << "1: could not set the test's limit; 2: could not read it; 3: raised or not lowered";
}

TEST(ReaderSandbox, ForbidsWritingSocketsAndNewProcessesButNotThreadsOrReading) {
  const ScratchDir dir("sandbox");
  const std::string target = (dir.path() / "written").string();
  const int status = in_child([&] {
    enter_reader_sandbox();
    int failures = 0;
    if (::open(target.c_str(), O_WRONLY | O_CREAT, 0600) >= 0 || errno != EACCES) failures |= 1;
    if (::socket(AF_UNIX, SOCK_STREAM, 0) >= 0 || errno != EPERM) failures |= 2;
    if (::fork() >= 0 || errno != EPERM) failures |= 4;
    if (::open("/proc/self/status", O_RDONLY) < 0) failures |= 8;
    bool ran = false;
    std::thread([&] { ran = true; }).join();
    if (!ran) failures |= 16;
    // A limit can be read (to say it), not changed, not even lowered.
    rlimit limit{};
    if (::getrlimit(RLIMIT_NOFILE, &limit) != 0) failures |= 32;
    const rlimit lower{limit.rlim_cur / 2, limit.rlim_max / 2};
    if (::setrlimit(RLIMIT_NOFILE, &lower) == 0 || errno != EPERM) failures |= 64;
    if (::prlimit(0, RLIMIT_NOFILE, &lower, nullptr) == 0 || errno != EPERM) failures |= 64;
    return failures;
  });
  EXPECT_EQ(status, 0) << "bits: 1 wrote a file, 2 made a socket, 4 forked, 8 could not read, 16 no thread, "
                          "32 could not read a limit, 64 changed one";
  EXPECT_FALSE(std::filesystem::exists(target));
}

}  // namespace
}  // namespace ph
