// The real `drape` program on bad input: for each case, exit status 2, one
// line "drape: error: ..." on stderr naming the key, flag or file, and the
// output directory not created. Also --dry-run, --version and --help.
#include <gtest/gtest.h>
#include <hdf5.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <functional>
#include <map>
#include <regex>
#include <sstream>
#include <string>
#include <vector>

#include "support/files.hpp"

extern char** environ;

namespace fs = std::filesystem;

namespace {

using drape::test::slurp;

fs::path tmp_dir() { return drape::test::process_tmp_dir("test_cli"); }

void spit(const fs::path& p, const std::string& text) { std::ofstream(p, std::ios::binary) << text; }

// Single-quoted for /bin/sh.
std::string sh(const std::string& arg) {
  std::string q = "'";
  for (char c : arg) q += c == '\'' ? std::string("'\\''") : std::string(1, c);
  return q + "'";
}

// The test program itself runs under MPI: its launcher's variables must not
// reach the child, or the child would think mpirun started it. Root may run it.
std::string clean_env() {
  static const char* const prefixes[] = {"OMPI_", "PMIX_", "ORTE_", "OPAL_", "PMI_", "HYDRA_", "MPI_"};
  std::string cmd = "env";
  for (char** e = environ; *e; ++e) {
    const std::string var(*e);
    const std::string name = var.substr(0, var.find('='));
    for (const char* p : prefixes)
      if (name.rfind(p, 0) == 0) cmd += " -u " + name;
  }
  return cmd + " OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 OMP_NUM_THREADS=1";
}

std::vector<std::string> lines_of(const std::string& text) {
  std::vector<std::string> lines;
  std::istringstream in(text);
  for (std::string line; std::getline(in, line);) lines.push_back(line);
  return lines;
}

struct Result {
  int status = -1;
  std::string out, err;
};

Result run_drape(const std::vector<std::string>& args, const std::string& tag) {
  const fs::path out = tmp_dir() / (tag + ".stdout"), err = tmp_dir() / (tag + ".stderr");
  std::string cmd = clean_env() + " " + sh(DRAPE_BINARY);
  for (const auto& a : args) cmd += " " + sh(a);
  cmd += " </dev/null >" + sh(out.string()) + " 2>" + sh(err.string());
  const int rc = std::system(cmd.c_str());
  Result r;
  r.status = rc != -1 && WIFEXITED(rc) ? WEXITSTATUS(rc) : -1;
  r.out = slurp(out);
  r.err = slurp(err);
  return r;
}

// A fabric file made from the shipped denim-A with one quantity replaced;
// returns the path and, in `line`, the line of the replaced quantity.
std::string fabric_with(const std::string& tag, const std::string& key, const std::string& replacement,
                        int& line) {
  std::string text = slurp(fs::path(DRAPE_SOURCE_DIR) / "data" / "kes" / "denim-A.toml");
  const std::regex re("(^|\n)" + key + "[ \t]*=[ \t]*\\{[^}\n]*\\}");
  std::smatch m;
  if (!std::regex_search(text, m, re)) {
    ADD_FAILURE() << "data/kes/denim-A.toml has no line '" << key << " = { ... }'";
    return "";
  }
  const auto pos = static_cast<size_t>(m.position(0)) + m[1].length();
  line = 1 + static_cast<int>(std::count(text.begin(), text.begin() + pos, '\n'));
  text.replace(pos, static_cast<size_t>(m.length(0) - m[1].length()), replacement);
  const fs::path p = tmp_dir() / (tag + "-fabric.toml");
  spit(p, text);
  return p.string();
}

// One bad invocation. In args and says, "{dir}" stands for the case's
// directory; `file`, when set, is written there as scene.toml first.
struct BadRun {
  const char* label;
  std::vector<std::string> args;
  std::vector<std::string> says;
  const char* file = nullptr;
};

std::string expand(std::string s, const std::string& dir) {
  for (size_t p; (p = s.find("{dir}")) != std::string::npos;) s.replace(p, 5, dir);
  return s;
}

// The checks every bad case shares.
void expect_refused(const std::string& label, std::vector<std::string> args, const std::vector<std::string>& says) {
  const fs::path outdir = tmp_dir() / (label + "-out");
  // --output first, so that a flag missing its value at the end stays last.
  args.insert(args.begin(), {"--output", outdir.string()});
  const Result r = run_drape(args, label);
  EXPECT_EQ(r.status, 2) << "stderr: " << r.err;
  EXPECT_EQ(r.err.rfind("drape: error: ", 0), 0u) << "stderr: " << r.err;
  EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << "not one line: " << r.err;
  for (const auto& s : says) EXPECT_NE(r.err.find(s), std::string::npos) << "'" << s << "' not in: " << r.err;
  EXPECT_FALSE(fs::exists(outdir)) << "output directory was created";
}

// Removes this process's temporary files when every test passed (they are
// kept after a failure, to look at).
struct CleanUp : ::testing::Environment {
  void TearDown() override {
    if (::testing::UnitTest::GetInstance()->failed_test_count() == 0) {
      std::error_code ec;
      fs::remove_all(fs::path(DRAPE_TEST_TMP) / ("test_cli-" + std::to_string(getpid())), ec);
    }
  }
};
const auto* const kCleanUp = ::testing::AddGlobalTestEnvironment(new CleanUp);

// Runs each case in its own directory (scene file written first).
void expect_all_refused(const std::vector<BadRun>& cases) {
  for (const BadRun& c : cases) {
    SCOPED_TRACE(c.label);
    const fs::path dir = tmp_dir() / c.label;
    fs::create_directories(dir);
    if (c.file) spit(dir / "scene.toml", c.file);
    std::vector<std::string> args, says;
    for (const auto& a : c.args) args.push_back(expand(a, dir.string()));
    for (const auto& s : c.says) says.push_back(expand(s, dir.string()));
    expect_refused(c.label, args, says);
  }
}

}  // namespace

// Cases are grouped into a few tests: each test process pays for MPI start-up.
TEST(CliBad, SceneConfig) {
  expect_all_refused({
    {"config_unknown_key", {"--config", "{dir}/scene.toml"}, {"{dir}/scene.toml:3:", "cloth.partcles", "cloth.particles?"},
     "# a scene\n[cloth]\npartcles = [9, 9]\n"},
    {"config_unknown_section", {"--config", "{dir}/scene.toml"}, {"{dir}/scene.toml:1:", "[clth]"}, "[clth]\ntile = 4\n"},
    {"config_wrong_type", {"--config", "{dir}/scene.toml"},
     {"{dir}/scene.toml:2:", "cloth.particles: expected an array of 2 integers, got a string"},
     "[cloth]\nparticles = \"big\"\n"},
    {"config_float_for_int", {"--config", "{dir}/scene.toml"}, {"{dir}/scene.toml:2:", "solver.steps"},
     "[solver]\nsteps = 10.5\n"},
    {"config_out_of_range", {"--config", "{dir}/scene.toml"}, {"{dir}/scene.toml:3:", "solver.dt", "> 0"},
     "[solver]\n\ndt = -0.001\n"},
    {"config_bad_enum", {"--config", "{dir}/scene.toml"}, {"{dir}/scene.toml:2:", "obstacle.shape", "cube"},
     "[obstacle]\nshape = \"cube\"\n"},
    {"config_syntax_error", {"--config", "{dir}/scene.toml"}, {"{dir}/scene.toml:2:", "TOML syntax error"},
     "[cloth]\ntile = = 4\n"},
    {"config_missing_file", {"--config", "{dir}/no-such-scene.toml"}, {"{dir}/no-such-scene.toml"}},
  });
}

TEST(CliBad, Flags) {
  expect_all_refused({
    {"flag_unknown", {"--bogus"}, {"--bogus"}},
    {"flag_threads_zero", {"--threads", "0"}, {"--threads"}},
    {"flag_threads_word", {"--threads", "many"}, {"--threads"}},
    {"flag_config_no_value", {"--config"}, {"--config"}},
    {"flag_set_no_equals", {"--set", "cloth.particles"}, {"--set cloth.particles", "section.key=value"}},
    {"flag_set_unknown_key", {"--set", "cloth.partciles=[9,9]"}, {"cloth.partciles", "cloth.particles?"}},
    {"flag_set_wrong_type", {"--set", "cloth.particles=9"}, {"--set cloth.particles=9", "cloth.particles"}},
    {"flag_set_out_of_range", {"--set", "solver.steps=0"}, {"--set solver.steps=0", "solver.steps"}},
    {"flag_set_not_toml", {"--set", "solver.dt=fast"}, {"--set solver.dt=fast", "solver.dt: expected a number"}},
  });
}

// Finite values whose products in the physics are not: refused as input,
// naming the key, not left to fail as a numerical error at step 1. Small
// short runs, so that a missing guard fails fast instead of simulating.
TEST(CliBad, OverflowingSizes) {
  expect_all_refused({
    {"size_area_overflows", {"--set", "cloth.size=[1e308,1e308]"}, {"--set cloth.size=[1e308,1e308]", "cloth.size", "too large"}},
    // The area overflows while the cloth's squared reach does not.
    {"size_area_alone_overflows", {"--set", "cloth.size=[1.5e154,1.5e154]"}, {"cloth.size", "too large: the cloth's area"}},
    {"size_spacing_underflows", {"--set", "cloth.size=[1e-200,1e-200]"}, {"cloth.size", "too small"}},
    {"size_mass_overflows", {"--set", "cloth.particles=[9,9]", "--set", "cloth.size=[8e152,8e152]"},
     {"cloth.size", "mass"}},
    {"obstacle_size_overflows", {"--set", "obstacle.size=[1e200,1,1]", "--set", "cloth.particles=[9,9]", "--set", "solver.steps=1"}, {"--set obstacle.size", "obstacle.size"}},
    {"obstacle_radius_overflows", {"--set", "obstacle.radius=1e300", "--set", "cloth.particles=[9,9]", "--set", "solver.steps=1"}, {"--set obstacle.radius", "obstacle.radius"}},
  });
}

// A cloth too large for the memory a rank has: refused before anything is
// allocated or written, saying how much it needs. The address space limit
// stands in for a small machine.
TEST(CliBad, TooLargeForMemory) {
  const fs::path outdir = tmp_dir() / "too-large-out";
  const fs::path err = tmp_dir() / "too-large.stderr";
  const std::string cmd = "ulimit -v 8000000 && " + clean_env() + " " + sh(DRAPE_BINARY) +
                          " --set cloth.particles=[10000,10000] --output " + sh(outdir.string()) +
                          " </dev/null >/dev/null 2>" + sh(err.string());
  const int rc = std::system(("/bin/sh -c " + sh(cmd)).c_str());
  const std::string e = slurp(err);
  ASSERT_TRUE(rc != -1 && WIFEXITED(rc)) << e;
  EXPECT_EQ(WEXITSTATUS(rc), 2) << e;
  EXPECT_EQ(e.rfind("drape: error: cloth.particles = [10000, 10000] needs about ", 0), 0u) << e;
  EXPECT_NE(e.find(" GB per rank, "), std::string::npos) << e;
  EXPECT_NE(e.find(" GB are available: use fewer particles"), std::string::npos) << e;
  EXPECT_EQ(std::count(e.begin(), e.end(), '\n'), 1) << e;
  EXPECT_FALSE(fs::exists(outdir)) << "output directory was created";
}

// A fabric that cannot be found, and fabric files with one bad value (made
// from the shipped denim-A): refused naming the file, line and key.
TEST(CliBad, Fabric) {
  expect_all_refused({
    {"fabric_unknown_name", {"--set", "cloth.fabric=no-such-fabric"}, {"no-such-fabric"}},
    {"fabric_missing_path", {"--set", "cloth.fabric={dir}/missing-fabric.toml"}, {"{dir}/missing-fabric.toml"}},
    {"fabric_missing_via_config", {"--config", "{dir}/scene.toml"}, {"no-such-fabric-either"},
     "[cloth]\nfabric = \"no-such-fabric-either\"\n"},
  });
  int line = 0;
  std::string path = fabric_with("lt", "LT", "LT = { value = 1.5, unit = \"1\" }", line);
  ASSERT_FALSE(path.empty());
  expect_refused("fabric_lt", {"--set", "cloth.fabric=" + path}, {path + ":" + std::to_string(line), "LT", "1.5"});

  path = fabric_with("unit", "EMT", "EMT = { value = 5.515 }", line);
  ASSERT_FALSE(path.empty());
  expect_refused("fabric_unit", {"--set", "cloth.fabric=" + path},
                 {path + ":" + std::to_string(line), "EMT", "unit"});

  path = fabric_with("b", "B", "B = { value = -0.172, unit = \"gf*cm^2/cm\" }", line);
  ASSERT_FALSE(path.empty());
  expect_refused("fabric_b", {"--set", "cloth.fabric=" + path}, {path + ":" + std::to_string(line), "B"});
}

// ------------------------------------------------------------ good input --

TEST(Cli, DryRunPrintsResolvedScene) {
  const fs::path outdir = tmp_dir() / "dry-out";
  const Result r = run_drape({"--dry-run", "--set", "cloth.particles=[9,9]", "--output", outdir.string()}, "dry");
  EXPECT_EQ(r.status, 0) << r.err;
  EXPECT_NE(r.out.find("particles = [9, 9]"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("[solver]"), std::string::npos) << r.out;
  EXPECT_FALSE(fs::exists(outdir)) << "--dry-run wrote output";
}

// What --dry-run prints is a scene file that resolves to itself.
TEST(Cli, DryRunOutputReadsBack) {
  const auto small = fs::path(DRAPE_SOURCE_DIR) / "run" / "scenes" / "small-box.toml";
  const Result first = run_drape({"--dry-run", "--config", small.string(), "--set", "solver.steps=7"}, "dry1");
  ASSERT_EQ(first.status, 0) << first.err;
  const fs::path resolved = tmp_dir() / "resolved.toml";
  spit(resolved, first.out);
  const Result second = run_drape({"--dry-run", "--config", resolved.string()}, "dry2");
  ASSERT_EQ(second.status, 0) << second.err;
  EXPECT_EQ(second.out, first.out);
  EXPECT_NE(first.out.find("steps = 7"), std::string::npos) << first.out;
}

// docs/configuration.md names every key the program accepts: each key of the
// resolved scene --dry-run prints, as `section.key`.
TEST(Cli, ConfigurationPageNamesEveryKey) {
  const Result r = run_drape({"--dry-run"}, "dry-keys");
  ASSERT_EQ(r.status, 0) << r.err;
  const std::string page = slurp(fs::path(DRAPE_SOURCE_DIR) / "docs" / "configuration.md");
  ASSERT_FALSE(page.empty()) << "no docs/configuration.md";
  std::istringstream lines(r.out);
  std::string line, section;
  int keys = 0;
  const std::regex header("^\\[([a-z_]+)\\]"), key("^([a-z_]+) *=");
  for (std::smatch m; std::getline(lines, line);) {
    if (std::regex_search(line, m, header)) section = m[1].str() + ".";
    else if (std::regex_search(line, m, key)) {
      const std::string name = "`" + section + m[1].str() + "`";
      ++keys;
      EXPECT_NE(page.find(name), std::string::npos) << name << " is not in docs/configuration.md";
    }
  }
  EXPECT_GE(keys, 40) << r.out;
}

// docs/configuration.md's tables are the program's own reference: all that
// follows the marker line is exactly what --help-config prints.
TEST(Cli, ConfigurationPageIsTheReference) {
  const Result r = run_drape({"--help-config"}, "help-config");
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_NE(r.out.find("| `solver.dt` | `0.001` | s | > 0 |"), std::string::npos) << r.out;
  const std::string page = slurp(fs::path(DRAPE_SOURCE_DIR) / "docs" / "configuration.md");
  const std::string marker = "<!-- generated by drape (help-config) from src/io/scene_schema.cpp: edit there -->\n";
  const size_t at = page.find(marker);
  ASSERT_NE(at, std::string::npos) << "docs/configuration.md has no line " << marker;
  const std::string hint =
      " differs from drape --help-config; refresh the page with: sed -i '/^<!-- generated by drape/q' "
      "docs/configuration.md && build/src/drape --help-config >> docs/configuration.md";
  const auto doc = lines_of(page.substr(at + marker.size())), ref = lines_of(r.out);
  const size_t first = 2 + std::count(page.begin(), page.begin() + at, '\n');  // the line after the marker
  for (size_t i = 0; i < std::max(doc.size(), ref.size()); ++i)
    ASSERT_EQ(i < doc.size() ? doc[i] : "(end of file)", i < ref.size() ? ref[i] : "(end of output)")
        << "docs/configuration.md:" << first + i << hint;
  EXPECT_TRUE(page.substr(at + marker.size()) == r.out) << "docs/configuration.md" << hint;
}

TEST(Cli, ExampleScenesDryRun) {
  for (const auto& e : fs::directory_iterator(fs::path(DRAPE_SOURCE_DIR) / "run" / "scenes")) {
    if (e.path().extension() != ".toml") continue;
    SCOPED_TRACE(e.path().string());
    const Result r = run_drape({"--dry-run", "--config", e.path().string()}, "scene-" + e.path().stem().string());
    EXPECT_EQ(r.status, 0) << r.err;
  }
}

TEST(Cli, Version) {
  const Result r = run_drape({"--version"}, "version");
  EXPECT_EQ(r.status, 0) << r.err;
  EXPECT_NE(r.out.find(std::string("drape ") + DRAPE_VERSION), std::string::npos) << r.out;
}

TEST(Cli, Help) {
  const Result r = run_drape({"--help"}, "help");
  EXPECT_EQ(r.status, 0) << r.err;
  for (const char* flag : {"--config", "--set", "--output", "--threads", "--dry-run", "--version", "--help-config"})
    EXPECT_NE(r.out.find(flag), std::string::npos) << flag << " not in: " << r.out;
}

// The run's peak resident set: in the timing table and report.json, in
// bytes, and plausible for a small cloth (above the program's own code and
// libraries, below what 9 x 9 particles could take).
TEST(Cli, ReportsPeakRss) {
  const fs::path dir = tmp_dir() / "peak-rss";
  const Result r = run_drape({"--set", "cloth.particles=[9,9]", "--set", "solver.steps=1", "--set",
                              "output.picture=false", "--output", dir.string()},
                             "peak-rss");
  ASSERT_EQ(r.status, 0) << r.err;
  std::smatch m;
  const std::string table = r.out;
  ASSERT_TRUE(std::regex_search(table, m, std::regex("peak RSS +([0-9.]+) +MB"))) << r.out;
  const double table_mb = std::stod(m[1]);
  const std::string report = slurp(dir / "report.json");
  ASSERT_TRUE(std::regex_search(report, m, std::regex("\"peak_rss_bytes\": ([0-9]+)"))) << report;
  const double bytes = std::stod(m[1]);
  EXPECT_GT(bytes, 4e6);
  EXPECT_LT(bytes, 2e9);
  EXPECT_NEAR(table_mb, 1e-6 * bytes, 0.06);
}

// --output naming an existing file: refused before anything is written, and
// the file is left as it was.
TEST(CliBad, OutputThatIsAFileIsRefusedAndUntouched) {
  const fs::path file = tmp_dir() / "not-a-directory";
  spit(file, "keep me\n");
  const Result r = run_drape(
      {"--set", "cloth.particles=[9,9]", "--set", "solver.steps=1", "--output", file.string()},
      "output-is-file");
  EXPECT_EQ(r.status, 2) << "stderr: " << r.err;
  EXPECT_EQ(r.err.rfind("drape: error: --output " + file.string() + ": cannot create the output directory", 0),
            0u)
      << r.err;
  EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
  EXPECT_EQ(slurp(file), "keep me\n");
}

// ------------------------------------------------------------ checkpoints --

namespace {

// A real checkpoint of a short run, made once per test process.
fs::path good_checkpoint() {
  static fs::path path;
  if (!path.empty()) return path;
  const fs::path dir = tmp_dir() / "ck-good";
  const Result r = run_drape({"--set", "cloth.particles=[9,9]", "--set", "solver.steps=2", "--set",
                              "output.checkpoint_every=1", "--set", "output.picture=false", "--quiet",
                              "--output", dir.string()},
                             "ck-good");
  EXPECT_EQ(r.status, 0) << r.err;
  path = dir / "checkpoint.h5";
  return path;
}

fs::path copy_with(const std::string& name, const std::function<void(std::string&)>& damage) {
  std::string bytes = slurp(good_checkpoint());
  damage(bytes);
  const fs::path p = tmp_dir() / name;
  spit(p, bytes);
  return p;
}

// Every file of a directory with its contents.
std::map<std::string, std::string> snapshot(const fs::path& dir) {
  std::map<std::string, std::string> files;
  for (const auto& e : fs::directory_iterator(dir)) files[e.path().filename().string()] = slurp(e.path());
  return files;
}

// The checkpoint with its format_version attribute set to 99.
fs::path future_version() {
  const fs::path p = tmp_dir() / "future.h5";
  fs::copy_file(good_checkpoint(), p, fs::copy_options::overwrite_existing);
  H5Eset_auto2(H5E_DEFAULT, nullptr, nullptr);
  const hid_t f = H5Fopen(p.c_str(), H5F_ACC_RDWR, H5P_DEFAULT);
  EXPECT_GE(f, 0);
  EXPECT_GE(H5Adelete(f, "format_version"), 0);
  const int64_t v = 99;
  const hid_t space = H5Screate(H5S_SCALAR);
  const hid_t a = H5Acreate2(f, "format_version", H5T_STD_I64LE, space, H5P_DEFAULT, H5P_DEFAULT);
  EXPECT_GE(H5Awrite(a, H5T_NATIVE_INT64, &v), 0);
  H5Aclose(a);
  H5Sclose(space);
  H5Fclose(f);
  return p;
}

// The checkpoint with one byte of /state/flags's object header changed as
// fuzz_checkpoint found it (56th byte 0 -> 4): HDF5 then fails to open the
// dataset (and leaks 456 bytes doing so, its own), which must be bad input.
fs::path damaged_dataset_header() {
  H5Eset_auto2(H5E_DEFAULT, nullptr, nullptr);
  const hid_t f = H5Fopen(good_checkpoint().c_str(), H5F_ACC_RDONLY, H5P_DEFAULT);
  EXPECT_GE(f, 0);
  H5O_info_t info{};
  EXPECT_GE(H5Oget_info_by_name2(f, "state/flags", &info, H5O_INFO_BASIC, H5P_DEFAULT), 0);
  H5Fclose(f);
  return copy_with("header.h5", [&](std::string& b) { b.at(size_t(info.addr) + 55) = 4; });
}

}  // namespace

// Damaged, truncated, foreign and misused checkpoints: refused before
// anything is written.
TEST(CliBad, Checkpoint) {
  const fs::path good = good_checkpoint();
  ASSERT_TRUE(fs::exists(good));
  const std::string size = std::to_string(fs::file_size(good));
  const fs::path truncated = copy_with("truncated.h5", [](std::string& b) { b.resize(b.size() / 3); });
  const fs::path flipped = copy_with("flipped.h5", [](std::string& b) { b[b.size() / 2] ^= 0x10; });
  const fs::path text = tmp_dir() / "text.h5";
  spit(text, "not a checkpoint\n");
  const fs::path output = good.parent_path() / "drape.h5";
  const fs::path future = future_version();
  const fs::path header = damaged_dataset_header();
  struct Case {
    const char* label;
    std::vector<std::string> args, says;
  };
  const std::vector<Case> cases = {
      {"ck_missing", {"--restart", (tmp_dir() / "nope.h5").string()}, {"nope.h5", "no such file"}},
      {"ck_directory", {"--restart", good.parent_path().string()}, {"is a directory"}},
      {"ck_text", {"--restart", text.string()}, {text.string(), "not an HDF5 file"}},
      {"ck_truncated", {"--restart", truncated.string()}, {truncated.string()}},
      {"ck_flipped", {"--restart", flipped.string()}, {flipped.string(), "damaged"}},
      {"ck_flipped_dry", {"--dry-run", "--restart", flipped.string()}, {flipped.string(), "damaged"}},
      {"ck_header", {"--restart", header.string()}, {header.string(), "dataset 'flags'"}},
      {"ck_foreign", {"--restart", output.string()}, {output.string(), "not a drape checkpoint"}},
      {"ck_version", {"--restart", future.string()}, {"format version 99"}},
      {"ck_with_config", {"--restart", good.string(), "--config", "x.toml"}, {"--config cannot be combined"}},
      {"ck_physics_change", {"--restart", good.string(), "--set", "solver.dt=0.1"},
       {"solver.dt cannot change on --restart"}},
      {"ck_bad_allowed_value", {"--restart", good.string(), "--set", "solver.steps=0"}, {"solver.steps"}},
  };
  const auto before = snapshot(good.parent_path());
  for (const Case& c : cases) {
    SCOPED_TRACE(c.label);
    expect_refused(c.label, c.args, c.says);
  }
  // Without --output a restart writes beside its checkpoint: a refused one
  // leaves that directory as it was, and so does a dry run of a good one.
  const Result r = run_drape({"--restart", good.string(), "--set", "cloth.tile=3"}, "ck-in-place");
  EXPECT_EQ(r.status, 2) << r.err;
  const Result dry = run_drape({"--dry-run", "--restart", good.string()}, "ck-dry");
  EXPECT_EQ(dry.status, 0) << dry.err;
  EXPECT_NE(dry.out.find("# restart from"), std::string::npos) << dry.out;
  EXPECT_EQ(snapshot(good.parent_path()), before);
}

// A run on 2 ranks refused on rank 0 alone: exit 2 from every rank, one
// message saying `says`, and no output directory.
void expect_refused_on_two_ranks(const std::string& label, const std::string& sets, const std::string& says) {
  const fs::path outdir = tmp_dir() / (label + "-out");
  const fs::path err = tmp_dir() / (label + ".stderr");
  const std::string cmd = clean_env() + " " + sh(MPIEXEC) + " -n 2 " + sh(DRAPE_BINARY) + " " + sets +
                          " --output " + sh(outdir.string()) + " </dev/null >/dev/null 2>" + sh(err.string());
  const int rc = std::system(cmd.c_str());
  EXPECT_TRUE(WIFEXITED(rc) && WEXITSTATUS(rc) == 2) << "status " << rc;
  const std::string text = slurp(err);
  size_t ours = 0;
  for (size_t p = 0; (p = text.find("drape: error: ", p)) != std::string::npos; ++p) ++ours;
  EXPECT_EQ(ours, 1u) << text;
  EXPECT_NE(text.find(says), std::string::npos) << text;
  EXPECT_FALSE(fs::exists(outdir));
}

// MPI settings: more ranks than tiles.
TEST(CliBad, MoreRanksThanTiles) {
  expect_refused_on_two_ranks("ranks", "--set 'cloth.particles=[8,8]' --set cloth.tile=8",
                              "2 ranks but the cloth has only 1 tile(s)");
}

// An AMRC checkpoint whose tree is damaged (one leaf level above
// amrc.max_level): the digest cannot be checked before the mesh is made from
// the tree, so the tree itself is refused, exit 2, nothing written.
TEST(CliBad, CheckpointWithADamagedTree) {
  const fs::path dir = tmp_dir() / "ck-tree";
  const Result r = run_drape({"--set", "cloth.particles=[17,17]", "--set", "amrc.enabled=true", "--set",
                              "amrc.max_level=2", "--set", "solver.steps=2", "--set", "output.checkpoint_every=2",
                              "--set", "output.picture=false", "--quiet", "--output", dir.string()},
                             "ck-tree");
  ASSERT_EQ(r.status, 0) << r.err;
  const fs::path damaged = tmp_dir() / "tree-damaged.h5";
  fs::copy_file(dir / "checkpoint.h5", damaged, fs::copy_options::overwrite_existing);
  H5Eset_auto2(H5E_DEFAULT, nullptr, nullptr);
  const hid_t f = H5Fopen(damaged.c_str(), H5F_ACC_RDWR, H5P_DEFAULT);
  ASSERT_GE(f, 0);
  const hid_t ds = H5Dopen2(f, "amrc_levels", H5P_DEFAULT);
  ASSERT_GE(ds, 0);
  std::vector<uint8_t> levels(16 * 16);
  ASSERT_GE(H5Dread(ds, H5T_NATIVE_UINT8, H5S_ALL, H5S_ALL, H5P_DEFAULT, levels.data()), 0);
  levels[0] = 7;
  ASSERT_GE(H5Dwrite(ds, H5T_NATIVE_UINT8, H5S_ALL, H5S_ALL, H5P_DEFAULT, levels.data()), 0);
  H5Dclose(ds);
  H5Fclose(f);
  const fs::path out = tmp_dir() / "ck-tree-out";
  const Result bad = run_drape({"--restart", damaged.string(), "--output", out.string()}, "ck-tree-bad");
  EXPECT_EQ(bad.status, 2) << bad.err;
  EXPECT_NE(bad.err.find("AMRC tree is damaged"), std::string::npos) << bad.err;
  EXPECT_EQ(std::count(bad.err.begin(), bad.err.end(), '\n'), 1) << bad.err;
  EXPECT_FALSE(fs::exists(out));
}

// A restart takes its thread count from its own launch (OMP_NUM_THREADS,
// --threads or --set parallel.threads), not from the run that wrote the
// checkpoint with --threads 2.
TEST(Cli, RestartTakesThisLaunchsThreads) {
  const fs::path dir = tmp_dir() / "ck-threads";
  const Result r = run_drape({"--set", "cloth.particles=[9,9]", "--threads", "2", "--set", "solver.steps=2", "--set",
                              "output.checkpoint_every=2", "--set", "output.picture=false", "--quiet", "--output",
                              dir.string()},
                             "ck-threads");
  ASSERT_EQ(r.status, 0) << r.err;
  const std::regex two("\"threads\": 2\\b"), one("\"threads\": 1\\b");
  ASSERT_TRUE(std::regex_search(slurp(dir / "report.json"), two));
  const std::string ck = (dir / "checkpoint.h5").string();
  struct Case {
    std::vector<std::string> args;
    const std::regex& threads;
  };
  const std::vector<Case> cases = {{{}, one}, {{"--set", "parallel.threads=2"}, two}, {{"--threads", "2"}, two}};
  int k = 0;
  for (const Case& c : cases) {
    const fs::path out = tmp_dir() / ("ck-threads-" + std::to_string(k++));
    std::vector<std::string> args = {"--restart", ck, "--set", "solver.steps=3", "--quiet", "--output", out.string()};
    args.insert(args.end(), c.args.begin(), c.args.end());
    const Result rr = run_drape(args, out.filename().string());
    ASSERT_EQ(rr.status, 0) << rr.err;
    EXPECT_TRUE(std::regex_search(slurp(out / "report.json"), c.threads)) << out;
  }
}

// A checkpoint of 3 x 3 tiles with one value of its last particle's x1
// changed: on 2 ranks only the rank holding that particle reads it, and the
// digest summed over the ranks refuses the file on both.
TEST(CliBad, DamagedCheckpointOnTwoRanks) {
  const fs::path dir = tmp_dir() / "ck-tiles";
  const Result r = run_drape({"--set", "cloth.particles=[9,9]", "--set", "cloth.tile=3", "--set", "solver.steps=2",
                              "--set", "output.checkpoint_every=1", "--set", "output.picture=false", "--quiet",
                              "--output", dir.string()},
                             "ck-tiles");
  ASSERT_EQ(r.status, 0) << r.err;
  const fs::path good = dir / "checkpoint.h5";
  H5Eset_auto2(H5E_DEFAULT, nullptr, nullptr);
  const hid_t f = H5Fopen(good.c_str(), H5F_ACC_RDONLY, H5P_DEFAULT);
  ASSERT_GE(f, 0);
  const hid_t ds = H5Dopen2(f, "state/x1", H5P_DEFAULT);
  const haddr_t at = H5Dget_offset(ds);  // contiguous: the values start there
  H5Dclose(ds);
  H5Fclose(f);
  ASSERT_NE(at, HADDR_UNDEF);
  const size_t last_x = size_t(at) + (81 - 1) * 3 * sizeof(double);
  const fs::path damaged = tmp_dir() / "tiles-damaged.h5";
  std::string bytes = slurp(good);
  bytes.at(last_x) ^= 0x01;  // the lowest bit of its x: still a plausible number
  spit(damaged, bytes);
  expect_refused_on_two_ranks("ck-tiles-damaged", "--restart " + sh(damaged.string()), "damaged");
  expect_refused_on_two_ranks("ck-tiles-damaged-dry", "--dry-run --restart " + sh(damaged.string()), "damaged");
  // The undamaged file restarts on 2 ranks.
  const std::string cmd = clean_env() + " " + sh(MPIEXEC) + " -n 2 " + sh(DRAPE_BINARY) + " --restart " +
                          sh(good.string()) + " --set solver.steps=3 --quiet </dev/null >/dev/null 2>&1";
  const int rc = std::system(cmd.c_str());
  EXPECT_TRUE(WIFEXITED(rc) && WEXITSTATUS(rc) == 0) << "status " << rc;
}

// Keys added with checkpoints, AMRC and rebalancing: out-of-range values and a
// combination the program cannot run are refused before anything is written.
TEST(CliBad, CheckpointAndAmrcKeys) {
  expect_all_refused({
      {"key_checkpoint_every", {"--set", "output.checkpoint_every=-1"}, {"output.checkpoint_every", ">= 0"}},
      {"key_end_time", {"--set", "solver.end_time=-0.5"}, {"solver.end_time", ">= 0"}},
      {"key_amrc_level", {"--set", "amrc.max_level=11"}, {"amrc.max_level", "[0, 10]"}},
      {"key_amrc_thresholds", {"--set", "amrc.coarsen=0.5"}, {"amrc.coarsen", "amrc.refine"}},
      {"key_amrc_every", {"--set", "amrc.every=0"}, {"amrc.every", ">= 1"}},
      {"key_coarsen_speed", {"--set", "amrc.coarsen_speed=-0.1"}, {"amrc.coarsen_speed", ">= 0"}},
      {"key_amrc_indicator", {"--set", "amrc.indicator=\"curvature\""},
       {"amrc.indicator", "angle, deflection", "curvature"}},
      {"key_imbalance", {"--set", "parallel.imbalance=0.9"}, {"parallel.imbalance", ">= 1"}},
      {"key_reversal", {"--set", "cloth.shear_reversal=0.5"}, {"cloth.shear_reversal", "> 1"}},
      {"key_compression", {"--set", "cloth.compression=-0.1"}, {"cloth.compression", "[0, 1]"}},
      {"key_start_spacing", {"--set", "amrc.start_spacing=-0.04"}, {"amrc.start_spacing", ">= 0"}},
      {"key_stage_drag", {"--set", "amrc.stage_drag=-1"}, {"amrc.stage_drag", ">= 0"}},
      {"key_amrc_numeric", {"--set", "cloth.particles=[9,9]", "--set", "amrc.enabled=true", "--set",
                            "solver.gradient=numeric"},
       {"amrc.enabled", "analytic"}},
      {"key_self_numeric", {"--set", "cloth.particles=[9,9]", "--set", "solver.self_contact=true", "--set",
                            "solver.gradient=numeric"},
       {"solver.self_contact", "analytic"}},
  });
}

// ------------------------------------------------------- what was solved --

namespace {

// One field of report.json as its text ("newton" with the quotes, 0.03125).
std::string report_field(const std::string& json, const std::string& key) {
  const std::regex re("\"" + key + "\": (\"[^\"]*\"|[^,\n}]*)");
  std::smatch m;
  return std::regex_search(json, m, re) ? m[1].str() : "(no " + key + ")";
}

// The closing line: the one that starts "done in".
std::string closing_line(const std::string& out) {
  const size_t p = out.find("done in ");
  return p == std::string::npos ? "(no closing line)" : out.substr(p, out.find('\n', p) - p);
}

}  // namespace

// report.json and the closing line say what was solved. Grid sequencing on a
// 65 x 65 grid with start_spacing 0.04 m runs on the level-1 mesh (33 x 33,
// spacing 2/64 m) with the stage drag; three steps do not bring it to rest.
// Its 1089 particles take the multigrid under the default `auto`.
TEST(Cli, ReportSaysWhatWasSolvedOnACoarserMesh) {
  const fs::path outdir = tmp_dir() / "solved-seq";
  const Result r = run_drape({"--set", "cloth.particles=[65,65]", "--set", "amrc.start_spacing=0.04", "--set",
                              "solver.steps=3", "--output", outdir.string()},
                             "solved-seq");
  ASSERT_EQ(r.status, 0) << r.err;
  const std::string j = slurp(outdir / "report.json");
  EXPECT_EQ(report_field(j, "particles"), "4225");
  EXPECT_EQ(report_field(j, "method"), "\"newton\"");
  EXPECT_EQ(report_field(j, "preconditioner"), "\"auto\"");
  EXPECT_EQ(report_field(j, "stage_preconditioner"), "\"multigrid\"");
  EXPECT_EQ(report_field(j, "drag"), "10");
  EXPECT_EQ(report_field(j, "pair_builds"), "1");  // self-contact on by default: its list built once in three steps
  EXPECT_EQ(report_field(j, "stage_drag"), "10");
  EXPECT_EQ(report_field(j, "particles_solved"), "1089");
  EXPECT_EQ(report_field(j, "final_spacing"), "0.03125");
  EXPECT_EQ(report_field(j, "unconverged_steps"), "0");
  // One stage, which took every step: its counts are the run's.
  EXPECT_EQ(report_field(j, "stage_steps"), "3");
  EXPECT_EQ(report_field(j, "stage_newton_iterations"), report_field(j, "newton_iterations"));
  EXPECT_EQ(report_field(j, "stage_linear_iterations"), report_field(j, "linear_iterations"));
  EXPECT_EQ(report_field(j, "stage_evaluations"), report_field(j, "evaluations"));
  EXPECT_NE(report_field(j, "stage_multigrid_builds"), "0");  // the multigrid
  EXPECT_EQ(report_field(j, "stage_rest_guesses"), "0");     // three steps of free fall: the fall's guess
  EXPECT_NE(report_field(j, "stage_newton_iterations"), "0");
  // The first line names the grid and the mesh solved first.
  EXPECT_NE(r.out.find("65 x 65 grid (1089 particles free), solved first on the level-1 mesh (spacing 31.2 mm)"),
            std::string::npos) << r.out;
  const std::string line = closing_line(r.out);
  EXPECT_NE(line.find("on the level-1 mesh (1089 particles solved, spacing 31.2 mm; the grid is 65 x 65)"),
            std::string::npos) << line;
  EXPECT_NE(line.find("newton with auto preconditioner"), std::string::npos) << line;
  EXPECT_EQ(line.find("unconverged"), std::string::npos) << line;
  // The picture says it too (its PNG tEXt chunk).
  const std::string png = slurp(outdir / "drape.png");
  const std::string chunk = std::string("tEXtDescription") + '\0' +
                            "box-drape, 65 x 65 grid: on the level-1 mesh, 1089 particles solved, spacing 31.2 mm; "
                            "newton with auto preconditioner; drag 10/s; t = ";
  EXPECT_NE(png.find(chunk), std::string::npos) << "drape.png has no such description";
}

// The paper's CG on the finest grid, with the scene's own drag: no stage drag,
// no preconditioner, every particle solved, and no mesh named. A step limit
// of 2 iterations with dt_min = dt leaves steps unconverged: both say how many.
TEST(Cli, ReportSaysWhatWasSolvedOnTheFinestMesh) {
  const fs::path outdir = tmp_dir() / "solved-cg";
  const auto small = fs::path(DRAPE_SOURCE_DIR) / "run" / "scenes" / "small-box.toml";
  const Result r = run_drape({"--config", small.string(), "--set", "cloth.particles=[17,17]", "--set",
                              "solver.method=cg", "--set", "solver.drag=2", "--set", "solver.steps=150", "--set",
                              "solver.max_iterations=2", "--set", "solver.dt_min=0.001", "--set",
                              "output.picture=false", "--set", "output.every=0", "--output", outdir.string()},
                             "solved-cg");
  ASSERT_EQ(r.status, 0) << r.err;
  const std::string j = slurp(outdir / "report.json");
  EXPECT_EQ(report_field(j, "method"), "\"cg\"");
  EXPECT_EQ(report_field(j, "preconditioner"), "\"none\"");
  EXPECT_EQ(report_field(j, "drag"), "2");
  EXPECT_EQ(report_field(j, "stage_drag"), "0");
  EXPECT_EQ(report_field(j, "particles_solved"), "289");
  EXPECT_EQ(report_field(j, "final_spacing"), "0.0625");
  const std::string unconverged = report_field(j, "unconverged_steps");
  ASSERT_NE(unconverged, "0") << "the case meant to leave steps unconverged converged";
  EXPECT_NE(r.out.find("17 x 17 grid (289 particles free), fabric"), std::string::npos) << r.out;
  const std::string line = closing_line(r.out);
  EXPECT_EQ(line.find("level-"), std::string::npos) << line;
  EXPECT_NE(line.find("cg with no preconditioner"), std::string::npos) << line;
  EXPECT_NE(line.find(", " + unconverged + " unconverged step(s)"), std::string::npos) << line;
}

// The safety net's projections are in the closing line when there are any:
// one Newton iteration per 20 ms step against a micrometre contact layer
// lets the cloth fall into the box top, and each particle found inside is set
// back on the surface. The same run with a working layer needs none, and
// its line says nothing of them.
TEST(Cli, ClosingLineCountsTheSafetyNetsProjections) {
  const auto small = fs::path(DRAPE_SOURCE_DIR) / "run" / "scenes" / "small-box.toml";
  const std::vector<std::string> base = {"--config", small.string(), "--set", "cloth.particles=[17,17]", "--set",
                                         "amrc.start_spacing=0", "--set", "cloth.height=0.40001", "--set",
                                         "solver.steps=10", "--set", "output.picture=false", "--set", "output.every=0"};
  for (int thin = 0; thin < 2; ++thin) {
    std::vector<std::string> args = base;
    const fs::path outdir = tmp_dir() / ("net-" + std::to_string(thin));
    if (thin)
      args.insert(args.end(), {"--set", "solver.contact_thickness=1e-6", "--set", "solver.max_iterations=1", "--set",
                               "solver.dt=0.02", "--set", "solver.dt_min=0.02", "--set", "solver.dt_max=0.02"});
    args.insert(args.end(), {"--output", outdir.string()});
    const Result r = run_drape(args, "net-" + std::to_string(thin));
    ASSERT_EQ(r.status, 0) << r.err;
    const std::string projections = report_field(slurp(outdir / "report.json"), "projections");
    const std::string line = closing_line(r.out);
    if (!thin) {
      EXPECT_EQ(projections, "0");
      EXPECT_EQ(line.find("safety net"), std::string::npos) << line;
      continue;
    }
    ASSERT_NE(projections, "0") << "the case meant to reach the safety net did not";
    EXPECT_NE(line.find(", " + projections + " particle(s) set back on a surface by the safety net"),
              std::string::npos)
        << line;
  }
}

// Newton with the multigrid preconditioner: report.json counts Newton's
// steps and the linear iterations (the `iterations` of a Newton run) and
// lists the levels (finest first, each coarser, the finest cycled), and the
// closing line names the preconditioner.
TEST(Cli, ReportCountsNewtonAndMultigrid) {
  const fs::path outdir = tmp_dir() / "solved-mg";
  const auto small = fs::path(DRAPE_SOURCE_DIR) / "run" / "scenes" / "small-box.toml";
  const Result r = run_drape({"--config", small.string(), "--set", "cloth.particles=[33,33]", "--set",
                              "amrc.start_spacing=0", "--set", "solver.preconditioner=\"multigrid\"", "--set",
                              "solver.end_time=0.15", "--set", "solver.steps=1000", "--set", "output.picture=false",
                              "--set", "output.every=0",
                              "--output", outdir.string()},
                             "solved-mg");
  ASSERT_EQ(r.status, 0) << r.err;
  const std::string j = slurp(outdir / "report.json");
  EXPECT_EQ(report_field(j, "preconditioner"), "\"multigrid\"");
  const long newton = std::stol(report_field(j, "newton_iterations"));
  EXPECT_GT(newton, 0);
  EXPECT_EQ(report_field(j, "linear_iterations"), report_field(j, "iterations"));
  EXPECT_GE(std::stol(report_field(j, "linear_iterations")), newton);
  const size_t at = j.find("\"multigrid\": [");
  ASSERT_NE(at, std::string::npos) << j;
  const std::string levels = j.substr(at, j.find(']', at) - at);
  std::vector<long> particles, cycles;
  const std::regex re("\"particles\": ([0-9]+),[^}]*?\"cycles\": ([0-9]+)");
  for (std::sregex_iterator m(levels.begin(), levels.end(), re), e; m != e; ++m) {
    particles.push_back(std::stol((*m)[1].str()));
    cycles.push_back(std::stol((*m)[2].str()));
  }
  ASSERT_GE(particles.size(), 2u) << levels;
  EXPECT_EQ(particles[0], std::stol(report_field(j, "particles_solved")));
  for (size_t k = 1; k < particles.size(); ++k) EXPECT_LT(particles[k], particles[k - 1]) << levels;
  // One V-cycle a CG iteration: before the first, and after each but the last.
  EXPECT_EQ(cycles[0], std::stol(report_field(j, "linear_iterations"))) << levels;
  EXPECT_NE(closing_line(r.out).find("newton with multigrid preconditioner"), std::string::npos) << r.out;
}

// max_penetration_written measures the surface as written (inactive
// particles filled in on their leaves), max_penetration the solved particles
// only: on the finest mesh they are the same particles; on a coarser mesh the
// written surface has more, so it cannot penetrate less.
TEST(Cli, PenetrationOnTheWrittenSurface) {
  const auto small = fs::path(DRAPE_SOURCE_DIR) / "run" / "scenes" / "small-box.toml";
  double solved[2], written[2];
  // 33 x 33 on its finest mesh; 65 x 65 sequenced from level-2 leaves (17 x 17).
  const char* spacing[2] = {"amrc.start_spacing=0", "amrc.start_spacing=0.07"};
  for (int k = 0; k < 2; ++k) {
    const fs::path outdir = tmp_dir() / ("pen-" + std::to_string(k));
    const Result r = run_drape({"--config", small.string(), "--set", k == 0 ? "cloth.particles=[33,33]" : "cloth.particles=[65,65]",
                                "--set", spacing[k], "--set", "solver.steps=2000", "--set", "solver.end_time=0.3", "--set",
                                "output.picture=false", "--set", "output.every=0", "--output", outdir.string()},
                               "pen-" + std::to_string(k));
    ASSERT_EQ(r.status, 0) << r.err;
    const std::string j = slurp(outdir / "report.json");
    solved[k] = std::stod(report_field(j, "max_penetration"));
    written[k] = std::stod(report_field(j, "max_penetration_written"));
    if (k == 1) {
      EXPECT_NE(report_field(j, "final_level"), "0");  // the coarse case ran coarse
    }
  }
  EXPECT_EQ(written[0], solved[0]);
  EXPECT_GE(written[1], solved[1]);
  // The coarse mesh's contact layer is half its own cell diagonal, so the
  // surface filled in between its particles clears the box top's edges too
  // (with half the finest spacing it cut them by about a millimetre).
  EXPECT_EQ(written[1], 0.0);
}

// With AMRC, final_spacing is the finest leaf's: a flat cloth started on
// level-1 leaves (start_spacing 0.04 m on a 65 x 65 grid) merges them all to
// level 2 at the first adaptation (step 3), 17 x 17 particles 62.5 mm apart.
TEST(Cli, ReportGivesTheFinestLeafSpacingWithAmrc) {
  const fs::path outdir = tmp_dir() / "solved-amrc";
  const auto small = fs::path(DRAPE_SOURCE_DIR) / "run" / "scenes" / "small-box.toml";
  const Result r = run_drape({"--config", small.string(), "--set", "amrc.enabled=true", "--set", "amrc.max_level=2",
                              "--set", "amrc.start_spacing=0.04", "--set", "solver.steps=3", "--set",
                              "output.picture=false", "--output", outdir.string()},
                             "solved-amrc");
  ASSERT_EQ(r.status, 0) << r.err;
  const std::string j = slurp(outdir / "report.json");
  EXPECT_EQ(report_field(j, "particles"), "4225");
  EXPECT_EQ(report_field(j, "particles_solved"), "289");
  EXPECT_EQ(report_field(j, "final_spacing"), "0.0625");
  EXPECT_EQ(report_field(j, "stage_drag"), "0");  // AMRC is not grid sequencing
  EXPECT_EQ(report_field(j, "drag"), "0");
}
