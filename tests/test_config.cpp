// Scene configuration: the embedded default, the example scenes, the TOML
// round trip, --set overrides and bad input refused with a one-line message
// that names the key and, for files, file:line.
#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <optional>
#include <sstream>
#include <string>
#include <vector>

#include "io/config.hpp"
#include "io/scene_schema.hpp"
#include "base/error.hpp"
#include "solver/scene.hpp"
#include "support/files.hpp"

namespace fs = std::filesystem;
using drape::InputError;
using drape::Scene;

namespace {

fs::path tmp_dir() { return drape::test::process_tmp_dir("test_config"); }

// A scene file named after the running test, so failures are easy to find.
std::string write_scene(const std::string& text, const std::string& tag = "") {
  const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
  std::string name = std::string(info->test_suite_name()) + "." + info->name() + tag;
  for (char& c : name)
    if (c == '/') c = '_';
  const fs::path p = tmp_dir() / (name + ".toml");
  std::ofstream(p) << text;
  return p.string();
}

// The keys whose values differ in a and b, bit for bit (-0.0 is not 0.0):
// each key's declaration compares its member (Config.EveryKeyReachesItsMember
// checks that every key's member is its own).
std::vector<std::string> differences(const Scene& a, const Scene& b) {
  std::vector<std::string> d;
  for (const drape::Parameter& p : drape::scene_parameters().all())
    if (!p.same(a, b)) d.push_back(p.full_name());
  return d;
}

void expect_same(const Scene& a, const Scene& b) { EXPECT_EQ(differences(a, b), std::vector<std::string>{}); }

std::vector<fs::path> example_scenes() {
  std::vector<fs::path> v;
  for (const auto& e : fs::directory_iterator(fs::path(DRAPE_SOURCE_DIR) / "run" / "scenes"))
    if (e.path().extension() == ".toml") v.push_back(e.path());
  std::sort(v.begin(), v.end());
  return v;
}

// load(print(s)) == s, and printing again gives the same text.
void expect_round_trip(const Scene& s) {
  const std::string text = drape::scene_to_toml(s);
  const Scene back = drape::load_scene(write_scene(text, ".roundtrip"), {});
  expect_same(back, s);
  EXPECT_EQ(drape::scene_to_toml(back), text);
}

// The InputError message of loading, or a test failure if none is thrown.
std::string error_of(const std::optional<std::string>& path, const std::vector<std::string>& sets = {}) {
  try {
    drape::load_scene(path, sets);
  } catch (const InputError& e) {
    return e.what();
  }
  ADD_FAILURE() << "no InputError";
  return "";
}

// Removes this process's temporary files when every test passed (they are
// kept after a failure, to look at).
struct CleanUp : ::testing::Environment {
  void TearDown() override {
    if (::testing::UnitTest::GetInstance()->failed_test_count() == 0) {
      std::error_code ec;
      fs::remove_all(fs::path(DRAPE_TEST_TMP) / ("test_config-" + std::to_string(getpid())), ec);
    }
  }
};
const auto* const kCleanUp = ::testing::AddGlobalTestEnvironment(new CleanUp);

}  // namespace

// ------------------------------------------------------------- good input --

TEST(Config, DefaultSceneIsSceneDefaults) {
  const Scene s = drape::load_scene(std::nullopt, {});
  expect_same(s, Scene{});
  // The paper's scene: a 1000 x 1000 cloth over a box, with friction on the
  // box and the floor (denim's mu, docs/validation.md).
  EXPECT_EQ(s.cloth.particles, (std::array<int, 2>{1000, 1000}));
  EXPECT_EQ(s.obstacle.shape, drape::ObstacleShape::Box);
  EXPECT_EQ(s.obstacle.friction, 0.3);
  EXPECT_EQ(s.obstacle.floor_friction, 0.3);
}

// box.toml spells out the default scene: each key it sets is at its default.
// It need not set every key (a curated, commented file); `drape --dry-run` and
// docs/configuration.md list them all.
TEST(Config, BoxSceneFileIsTheDefault) {
  const auto box = fs::path(DRAPE_SOURCE_DIR) / "run" / "scenes" / "box.toml";
  expect_same(drape::load_scene(box.string(), {}), Scene{});
}

// Each key's example value, set alone, changes that key and no other: the
// key is read into its own member (two keys bound to one member would both
// differ), and the example is not the default.
TEST(Config, EveryKeyReachesItsMember) {
  const auto& all = drape::scene_parameters().all();
  ASSERT_GE(all.size(), 50u);
  for (const drape::Parameter& p : all) {
    SCOPED_TRACE(p.full_name());
    ASSERT_FALSE(p.example.empty()) << "no example value declared";
    Scene s;
    try {
      s = drape::load_scene(std::nullopt, {p.full_name() + "=" + p.example_toml()});
    } catch (const InputError& e) {
      ADD_FAILURE() << "example " << p.example << " refused: " << e.what();
      continue;
    }
    EXPECT_EQ(differences(s, Scene{}), std::vector<std::string>{p.full_name()}) << "example " << p.example;
  }
}

// differences() is bitwise: a sign of zero and the last ulp count.
TEST(Config, DifferencesAreBitwise) {
  Scene a, b;
  b.cloth.height = std::nextafter(a.cloth.height, 1.0);
  EXPECT_EQ(differences(a, b), std::vector<std::string>{"cloth.height"});
  a.cloth.center = {0.0, 0.0};
  b = a;
  b.cloth.center = {-0.0, 0.0};
  EXPECT_EQ(differences(a, b), std::vector<std::string>{"cloth.center"});
}

TEST(Config, ExampleScenesLoad) {
  const auto scenes = example_scenes();
  ASSERT_GE(scenes.size(), 4u);
  for (const auto& p : scenes) {
    SCOPED_TRACE(p.string());
    EXPECT_NO_THROW(drape::load_scene(p.string(), {}));
  }
  const auto dir = fs::path(DRAPE_SOURCE_DIR) / "run" / "scenes";
  const Scene sphere = drape::load_scene((dir / "sphere.toml").string(), {});
  EXPECT_EQ(sphere.obstacle.shape, drape::ObstacleShape::Sphere);
  const Scene strip = drape::load_scene((dir / "cantilever.toml").string(), {});
  EXPECT_EQ(strip.obstacle.shape, drape::ObstacleShape::None);
  EXPECT_FALSE(strip.cloth.shear);
}

TEST(Config, EnumNames) {
  EXPECT_STREQ(to_string(drape::ObstacleShape::Box), "box");
  EXPECT_STREQ(to_string(drape::ObstacleShape::Sphere), "sphere");
  EXPECT_STREQ(to_string(drape::ObstacleShape::None), "none");
  EXPECT_STREQ(to_string(drape::GradientMode::Analytic), "analytic");
  EXPECT_STREQ(to_string(drape::GradientMode::Numeric), "numeric");
  EXPECT_STREQ(to_string(drape::Schedule::ActiveLists), "active-lists");
  EXPECT_STREQ(to_string(drape::Schedule::Static), "static");
  EXPECT_STREQ(to_string(drape::Schedule::Dynamic), "dynamic");
  EXPECT_STREQ(to_string(drape::Schedule::Guided), "guided");
}

TEST(Config, RoundTripDefaultAndExamples) {
  expect_round_trip(Scene{});
  for (const auto& p : example_scenes()) {
    SCOPED_TRACE(p.string());
    expect_round_trip(drape::load_scene(p.string(), {}));
  }
}

// Doubles that print badly with few digits, and a name that needs escapes.
TEST(Config, RoundTripAwkwardValues) {
  Scene s;
  s.name = "a \"quoted\" name\\with\ttabs\nand lines, \xC3\xA9t\xC3\xA9";
  s.cloth.size = {0.1 + 0.2, 1.0 / 3.0};
  s.cloth.height = 1e-300;
  s.cloth.center = {-0.0, 123456789.123456789};
  s.obstacle.center = {std::nextafter(0.2, 1.0), -1e-7, 5e-324};
  s.obstacle.shape = drape::ObstacleShape::Sphere;
  s.solver.dt = 2.0 / 3.0 * 1e-3;
  s.solver.gradient = drape::GradientMode::Numeric;
  s.solver.damping = 0.9999999999999999;
  s.parallel.schedule = drape::Schedule::Guided;
  s.cloth.fabric = "../data/my fabric.toml";
  expect_round_trip(s);
}

TEST(Config, ShortNumbersWhenExact) {
  const std::string text = drape::scene_to_toml(Scene{});
  EXPECT_NE(text.find("dt = 0.001 "), std::string::npos) << text;
  EXPECT_NE(text.find("size = [1.0, 1.0] "), std::string::npos) << text;
  EXPECT_NE(text.find("particles = [1000, 1000] "), std::string::npos) << text;
  EXPECT_NE(text.find("shape = \"box\""), std::string::npos) << text;
}

// The reference (docs/configuration.md's tables) has a row for each key
// --dry-run prints, with the same default, and lists an enumeration's names.
TEST(Config, ReferenceRowPerKeyWithItsDefault) {
  const std::string ref = drape::scene_reference();
  std::istringstream in(drape::scene_to_toml(Scene{}));
  std::string line, section;
  int rows = 0;
  while (std::getline(in, line)) {
    if (line.empty() || line[0] == '#') continue;
    if (line[0] == '[') {
      section = line.substr(1, line.find(']') - 1) + ".";
      continue;
    }
    const size_t eq = line.find(" = ");
    std::string value = line.substr(eq + 3, line.find("  #") - eq - 3);
    value.erase(value.find_last_not_of(' ') + 1);
    const std::string row = "| `" + section + line.substr(0, eq) + "` | `" + value + "` |";
    EXPECT_NE(ref.find("\n" + row), std::string::npos) << row;
    ++rows;
  }
  // 7 tables, each a heading, a blank line, the header and its rule; a blank line between.
  EXPECT_EQ(std::count(ref.begin(), ref.end(), '\n'), rows + 4 * 7 + 6) << "a row for a key --dry-run lacks";
  std::string shapes;
  for (auto e : {drape::ObstacleShape::Box, drape::ObstacleShape::Sphere, drape::ObstacleShape::None,
                 drape::ObstacleShape::Disc})
    shapes += std::string(shapes.empty() ? "`" : ", `") + to_string(e) + "`";
  EXPECT_NE(ref.find("| `obstacle.shape` | `\"box\"` |  | " + shapes + " |"), std::string::npos) << ref;
}

// The circular specimen is cut from a square grid, on the finest mesh only.
TEST(Config, DiscClothNeedsASquareAndNoAmrc) {
  EXPECT_NE(error_of(std::nullopt, {"cloth.shape=disc", "cloth.size=[0.3, 0.4]"}).find("cloth.size"),
            std::string::npos);
  EXPECT_NE(error_of(std::nullopt, {"cloth.shape=disc", "amrc.enabled=true"}).find("amrc.enabled"),
            std::string::npos);
  EXPECT_NO_THROW(drape::load_scene(std::nullopt, {"cloth.shape=disc", "obstacle.shape=disc"}));
}

TEST(Config, FileThenOverrides) {
  const std::string path = write_scene(
      "name = \"t\"\n[cloth]\nparticles = [33, 17]\ntile = 8\n[solver]\ndt = 1\ndt_max = 2\n");
  const Scene s = drape::load_scene(
      path, {"cloth.particles=[65,65]", "obstacle.shape=sphere", "solver.gradient=\"numeric\"",
             "cloth.fabric = ../my fabric.toml", "solver.steps=5", "cloth.shear=false",
             "parallel.schedule=dynamic", "obstacle.center=[0, 0.5, 1]", "name=my run"});
  EXPECT_EQ(s.cloth.particles, (std::array<int, 2>{65, 65}));  // the override wins
  EXPECT_EQ(s.cloth.tile, 8);                                  // the file stands
  EXPECT_EQ(s.solver.dt, 1.0);                                 // integer for a float key
  EXPECT_EQ(s.obstacle.shape, drape::ObstacleShape::Sphere);
  EXPECT_EQ(s.solver.gradient, drape::GradientMode::Numeric);
  EXPECT_EQ(s.cloth.fabric, "../my fabric.toml");
  EXPECT_EQ(s.solver.steps, 5);
  EXPECT_FALSE(s.cloth.shear);
  EXPECT_EQ(s.parallel.schedule, drape::Schedule::Dynamic);
  EXPECT_EQ(s.obstacle.center, (std::array<double, 3>{0, 0.5, 1}));
  EXPECT_EQ(s.name, "my run");
}

TEST(Config, LaterOverrideWins) {
  const Scene s = drape::load_scene(std::nullopt, {"solver.steps=3", "solver.steps=7"});
  EXPECT_EQ(s.solver.steps, 7);
}

// -------------------------------------------------------------- bad input --

// One bad scene file: its text, the line the error must point at, and
// fragments the one-line message must contain (the key, the problem).
struct BadFile {
  const char* label;
  const char* text;
  int line;
  std::vector<const char*> says;
};

const BadFile kBadFiles[] = {
    {"unknown_key", "# t\n[cloth]\npartcles = [9, 9]\n", 3,
     {"unknown key cloth.partcles", "did you mean cloth.particles?"}},
    {"unknown_section", "# t\n\n[clth]\ntile = 4\n", 3, {"unknown section [clth]", "did you mean [cloth]?"}},
    {"key_in_wrong_section", "[obstacle]\ndt = 0.001\n", 2, {"unknown key obstacle.dt", "did you mean solver.dt?"}},
    {"unknown_top_level", "name = \"x\"\nsteps = 5\n", 2, {"unknown key steps", "solver.steps"}},
    {"first_unknown_reported", "[solver]\nzzz = 1\naaa = 2\n", 2, {"solver.zzz"}},
    {"section_not_table", "\ncloth = 3\n", 2, {"cloth: expected a section [cloth], got an integer"}},
    {"wrong_type_string", "[cloth]\n\nparticles = \"big\"\n", 3,
     {"cloth.particles: expected an array of 2 integers, got a string"}},
    {"float_for_int", "[cloth]\ntile = 2.5\n", 2, {"cloth.tile: expected an integer, got a floating-point number"}},
    {"float_in_int_array", "[cloth]\nparticles = [9, 9.5]\n", 2,
     {"cloth.particles: expected an array of 2 integers, got a floating-point number"}},
    {"array_length", "[obstacle]\ncenter = [0, 0]\n", 2,
     {"obstacle.center: expected an array of 3 numbers, got an array of 2"}},
    {"string_in_float_array", "[cloth]\nsize = [1, \"1\"]\n", 2, {"cloth.size: expected an array of 2 numbers"}},
    {"wrong_type_bool", "[obstacle]\nfloor = 1\n", 2, {"obstacle.floor: expected a boolean", "got an integer"}},
    {"wrong_type_number", "[solver]\ndt = \"1ms\"\n", 2, {"solver.dt: expected a number, got a string"}},
    {"wrong_type_name", "name = 5\n", 1, {"name: expected a string, got an integer"}},
    {"dotted_key_table", "[obstacle]\nsize.x = 1\n", 2, {"obstacle.size: expected an array of 3 numbers, got a table"}},
    {"particles_too_few", "[cloth]\nparticles = [2, 100]\n", 2, {"cloth.particles", ">= 3", "[2, 100]"}},
    {"particles_overflow", "[cloth]\nparticles = [100000, 100000]\n", 2, {"cloth.particles", "at most"}},
    // Within int, beyond what the gather's int32 buffer offsets reach.
    {"particles_beyond_gather", "[cloth]\nparticles = [20000, 20000]\n", 2,
     {"cloth.particles", "at most 119304647", "[20000, 20000]"}},
    {"size_zero", "[cloth]\nsize = [1.0, 0.0]\n", 2, {"cloth.size", "> 0"}},
    {"tile_one", "[cloth]\ntile = 1\n", 2, {"cloth.tile: must be >= 2, got 1"}},
    {"height_below_floor", "[cloth]\nheight = -0.1\n", 2, {"cloth.height", ">= 0"}},
    {"obstacle_size_negative", "[obstacle]\nsize = [0.4, -0.4, 0.4]\n", 2, {"obstacle.size", "> 0"}},
    {"radius_zero", "[obstacle]\nradius = 0\n", 2, {"obstacle.radius: must be > 0, got 0"}},
    {"friction_negative", "[obstacle]\nfloor_friction = -0.2\n", 2, {"obstacle.floor_friction: must be >= 0, got -0.2"}},
    {"shape_unknown", "[obstacle]\nshape = \"cube\"\n", 2, {"obstacle.shape: must be one of box, sphere, none", "\"cube\""}},
    {"dt_negative", "[solver]\ndt = -0.001\n", 2, {"solver.dt: must be > 0, got -0.001"}},
    {"dt_above_max", "[solver]\ndt_max = 0.004\ndt = 0.01\n", 3, {"solver.dt", "[1e-05, 0.004]", "got 0.01"}},
    {"dt_min_above_max", "[solver]\ndt_min = 0.1\ndt_max = 0.01\ndt = 0.05\n", 2,
     {"solver.dt_min", "must be <= solver.dt_max"}},
    {"steps_zero", "[solver]\nsteps = 0\n", 2, {"solver.steps: must be >= 1, got 0"}},
    {"steps_huge", "[solver]\nsteps = 99999999999\n", 2, {"solver.steps", "out of range"}},
    {"max_iterations_zero", "[solver]\nmax_iterations = 0\n", 2, {"solver.max_iterations: must be >= 1"}},
    {"tolerance_zero", "[solver]\ntolerance = 0.0\n", 2, {"solver.tolerance: must be > 0"}},
    {"tolerance_nan", "[solver]\ntolerance = nan\n", 2, {"solver.tolerance: must be a finite number"}},
    {"gradient_unknown", "[solver]\ngradient = \"exact\"\n", 2, {"solver.gradient: must be one of analytic, numeric"}},
    {"damping_one", "[solver]\ndamping = 1\n", 2, {"solver.damping: must be in [0, 1)"}},
    {"every_negative", "[output]\nevery = -1\n", 2, {"output.every: must be >= 0"}},
    {"schedule_unknown", "[parallel]\nschedule = \"auto\"\n", 2,
     {"parallel.schedule: must be one of active-lists, static, dynamic, guided"}},
    {"chunk_zero", "[parallel]\nchunk = 0\n", 2, {"parallel.chunk: must be >= 1"}},
    {"threads_negative", "[parallel]\nthreads = -2\n", 2, {"parallel.threads", "got -2"}},
    {"name_empty", "name = \"\"\n", 1, {"name: must not be empty"}},
    {"syntax_unclosed_array", "# t\n[cloth]\nparticles = [9, 9\ntile = 4\n", 4,
     {"TOML syntax error", "expected comma or closing ']'"}},
    {"syntax_duplicate_key", "[solver]\nsteps = 3\nsteps = 4\n", 3, {"TOML syntax error"}},
    {"syntax_bare_string", "[obstacle]\nshape = box\n", 2, {"TOML syntax error"}},
};

// All cases in one process: each test process pays for MPI start-up.
TEST(ConfigBad, SceneFilesRefusedNamingKeyAndLine) {
  for (const BadFile& c : kBadFiles) {
    SCOPED_TRACE(c.label);
    const std::string path = write_scene(c.text, std::string(".") + c.label);
    const std::string msg = error_of(path);
    EXPECT_EQ(msg.find('\n'), std::string::npos) << msg;
    EXPECT_EQ(msg.rfind(path + ":" + std::to_string(c.line) + ":", 0), 0u)
        << "expected to start with " << path << ":" << c.line << ":, got: " << msg;
    for (const char* s : c.says) EXPECT_NE(msg.find(s), std::string::npos) << "'" << s << "' not in: " << msg;
  }
}

TEST(ConfigBad, SyntaxErrorHasColumn) {
  const std::string path = write_scene("[cloth]\ntile = = 4\n");
  const std::string msg = error_of(path);
  EXPECT_EQ(msg.rfind(path + ":2:", 0), 0u) << msg;
  // file:line:column: a third number before the description.
  const std::string rest = msg.substr(path.size() + 3);
  EXPECT_TRUE(std::isdigit(static_cast<unsigned char>(rest[0]))) << msg;
}

TEST(ConfigBad, MissingFile) {
  const std::string path = (tmp_dir() / "no-such-scene.toml").string();
  const std::string msg = error_of(path);
  EXPECT_NE(msg.find(path), std::string::npos) << msg;
  EXPECT_NE(msg.find("no such file"), std::string::npos) << msg;
}

TEST(ConfigBad, DirectoryAsFile) {
  const std::string msg = error_of(tmp_dir().string());
  EXPECT_NE(msg.find("directory"), std::string::npos) << msg;
}

// Bad --set overrides: the message starts with the --set it came from.
struct BadSet {
  const char* label;
  const char* set;
  std::vector<const char*> says;
};

const BadSet kBadSets[] = {
    {"no_equals", "cloth.particles", {"expected section.key=value"}},
    {"no_key", "=5", {"missing key"}},
    {"no_value", "solver.dt=", {"solver.dt: missing value"}},
    {"unknown_key", "cloth.partciles=[9,9]", {"unknown key cloth.partciles", "did you mean cloth.particles?"}},
    {"unknown_section", "clth.tile=4", {"unknown key clth.tile", "did you mean cloth.tile?"}},
    {"section_only", "cloth=4", {"unknown key cloth"}},
    {"not_toml", "solver.dt=fast", {"solver.dt: expected a number, got 'fast'"}},
    {"two_values", "solver.steps=3 4", {"solver.steps: expected an integer, got '3 4'"}},
    {"wrong_type", "cloth.particles=9", {"cloth.particles: expected an array of 2 integers, got an integer"}},
    {"float_for_int", "solver.steps=2.5", {"solver.steps: expected an integer"}},
    {"out_of_range", "solver.dt=-1", {"solver.dt: must be > 0, got -1"}},
    {"bad_enum", "obstacle.shape=cube", {"obstacle.shape: must be one of box, sphere, none"}},
    {"bad_bool", "cloth.shear=yes", {"cloth.shear: expected a boolean (true or false), got 'yes'"}},
    {"quoted_for_bool", "cloth.shear=\"true\"", {"cloth.shear: expected a boolean", "got a string"}},
    {"dt_max_below_dt", "solver.dt_max=1e-4", {"solver.dt", "[1e-05, 0.0001]"}},
    {"negative_memory", "solver.memory=-1", {"solver.memory: must be >= 0, got -1"}},
    {"negative_wall_limit", "solver.wall_limit=-5", {"solver.wall_limit: must be >= 0", "got -5"}},
    {"bad_method", "solver.method=fast", {"solver.method: must be one of newton, cg"}},
    {"clamp_too_many_rows", "cloth.clamp=1000", {"cloth.clamp: must be in [0, NI), got 1000"}},
    {"clamp_negative", "cloth.clamp=-1", {"cloth.clamp: must be in [0, NI), got -1"}},
    // Each form of a declared bound's words.
    {"particles_two", "cloth.particles=[2,9]", {"cloth.particles: NI and NJ must each be >= 3, got [2, 9]"}},
    {"size_zero", "cloth.size=[1.0,0]", {"cloth.size: sizes must be > 0, got [1.0, 0.0]"}},
    {"reversal_one", "cloth.bend_reversal=1",
     {"cloth.bend_reversal: must be 0 (the band taken literally) or > 1, got 1.0"}},
    {"threads_many", "parallel.threads=1025",
     {"parallel.threads: must be in [0, 1024] (0: OpenMP default), got 1025"}},
    {"fabric_empty", "cloth.fabric=\"\"", {"cloth.fabric: must not be empty"}},
};

TEST(ConfigBad, OverridesRefusedNamingTheOverride) {
  for (const BadSet& c : kBadSets) {
    SCOPED_TRACE(c.label);
    const std::string msg = error_of(std::nullopt, {"solver.steps=3", c.set});
    EXPECT_EQ(msg.find('\n'), std::string::npos) << msg;
    EXPECT_EQ(msg.rfind(std::string("--set ") + c.set + ": ", 0), 0u) << msg;
    for (const char* s : c.says) EXPECT_NE(msg.find(s), std::string::npos) << "'" << s << "' not in: " << msg;
  }
}

// An override fixes nothing the file got wrong: the unknown key still counts.
TEST(ConfigBad, OverrideDoesNotHideFileErrors) {
  const std::string path = write_scene("[cloth]\nparticle = [9, 9]\n");
  const std::string msg = error_of(path, {"cloth.particles=[9,9]"});
  EXPECT_EQ(msg.rfind(path + ":2:", 0), 0u) << msg;
}

// The error names the override, not the file, when the override set the value.
TEST(ConfigBad, OverrideOfFileKeyNamesOverride) {
  const std::string path = write_scene("[solver]\nsteps = 3\n");
  const std::string msg = error_of(path, {"solver.steps=0"});
  EXPECT_EQ(msg.rfind("--set solver.steps=0: solver.steps", 0), 0u) << msg;
}

// Each key's range ends where its documentation says: the last value
// allowed loads, the next one past it (a step or an ulp) is refused naming
// the key. Together with the messages above this pins every declared bound.
struct Edge {
  const char* key;
  const char* allowed;
  const char* refused;
};

const Edge kEdges[] = {
    {"name", "\"x\"", "\"\""},
    {"cloth.particles", "[3, 3]", "[3, 2]"},
    {"cloth.size", "[1e-3, 1.0]", "[1.0, 0.0]"},
    {"cloth.fabric", "\"x\"", "\"\""},
    {"cloth.tile", "2", "1"},
    {"cloth.bend_reversal", "1.0000000000000002", "1.0"},
    {"cloth.bend_reversal", "0.0", "0.5"},
    {"cloth.shear_reversal", "1.0000000000000002", "1.0"},
    {"cloth.shear_reversal", "0.0", "-1e-300"},
    {"cloth.stretch_reversal", "1.0", "0.9999999999999999"},
    {"cloth.stretch_reversal", "0.0", "1e-300"},
    {"cloth.compression", "1.0", "1.0000000000000002"},
    {"cloth.compression", "0.0", "-1e-300"},
    {"obstacle.size", "[0.4, 1e-300, 0.4]", "[0.4, 0.0, 0.4]"},
    {"obstacle.radius", "1e-300", "0.0"},
    {"solver.dt_min", "1e-300", "0.0"},
    {"solver.steps", "1", "0"},
    {"solver.max_iterations", "1", "0"},
    {"solver.tolerance", "1e-300", "0.0"},
    {"solver.damping", "0.9999999999999999", "1.0"},
    {"solver.damping", "0.0", "-1e-300"},
    {"solver.rest_speed", "0.0", "-1e-300"},
    {"solver.contact_thickness", "0.0", "-1e-300"},
    {"solver.memory", "0.0", "-1e-300"},
    {"solver.drag", "0.0", "-1e-300"},
    {"solver.wall_limit", "0.0", "-1e-300"},
    {"solver.end_time", "0.0", "-1e-300"},
    {"output.every", "0", "-1"},
    {"output.checkpoint_every", "0", "-1"},
    {"parallel.chunk", "1", "0"},
    {"parallel.threads", "1024", "1025"},
    {"parallel.threads", "0", "-1"},
    {"parallel.imbalance", "1.0", "0.9999999999999999"},
    {"amrc.max_level", "10", "11"},
    {"amrc.max_level", "0", "-1"},
    {"amrc.refine", "0.03", "0.0"},
    {"amrc.every", "1", "0"},
    {"amrc.coarsen_speed", "0.0", "-1e-300"},
    {"amrc.start_spacing", "0.0", "-1e-300"},
    {"amrc.stage_drag", "0.0", "-1e-300"},
};

TEST(ConfigBad, RangesEndWhereDocumented) {
  for (const Edge& e : kEdges) {
    SCOPED_TRACE(std::string(e.key) + " allows " + e.allowed + ", refuses " + e.refused);
    EXPECT_NO_THROW(drape::load_scene(std::nullopt, {std::string(e.key) + "=" + e.allowed}));
    const std::string set = std::string(e.key) + "=" + e.refused;
    const std::string msg = error_of(std::nullopt, {set});
    EXPECT_EQ(msg.rfind("--set " + set + ": " + e.key + ": ", 0), 0u) << msg;
  }
}
