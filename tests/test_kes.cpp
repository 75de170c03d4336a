// KES fabric data: the shipped fabrics load, convert to SI correctly, give
// bands with the KES energies, and bad files are refused with file:line + key.
#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <functional>
#include <initializer_list>
#include <string>
#include <utility>
#include <vector>

#include "base/error.hpp"
#include "io/kes.hpp"
#include "solver/band.hpp"

namespace drape {
namespace {

namespace fs = std::filesystem;

constexpr double kPi = 3.14159265358979323846;
constexpr double kGf = 9.80665e-3;  // N

const std::vector<std::string> kDenims = {"denim-A", "denim-B", "denim-C",
                                          "denim-D", "denim-E", "denim-F"};

// ------------------------------------------------------------ helpers

// A fresh directory per test under DRAPE_TEST_TMP, removed afterwards.
class TmpDir {
 public:
  TmpDir() {
    const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
    path_ = fs::path(DRAPE_TEST_TMP) /
            ("kes-" + std::string(info->name()) + "-" + std::to_string(::getpid()));
    fs::remove_all(path_);
    fs::create_directories(path_);
  }
  ~TmpDir() {
    std::error_code ec;
    fs::remove_all(path_, ec);
  }
  std::string write(const std::string& name, const std::string& text) const {
    const fs::path p = path_ / name;
    fs::create_directories(p.parent_path());
    std::ofstream(p) << text;
    return p.string();
  }
  const fs::path& path() const { return path_; }

 private:
  fs::path path_;
};

// A valid fabric; tests break one line of it at a time.
const std::string kGood = R"(description = "test fabric"
[source]
reference = "unit test"
[tensile]
EMT = { value = 5.0, unit = "%" }
LT = { value = 0.7, unit = "1" }
RT = { value = 50.0, unit = "%" }
[bending]
B = { warp = 0.18, weft = 0.16, unit = "gf*cm^2/cm" }
2HB = { value = 0.14, unit = "gf*cm/cm" }
[shear]
G = { value = 2.0, unit = "gf/cm/deg" }
2HG = { value = 4.0, unit = "gf/cm" }
[physical]
T = { value = 1.0, unit = "mm" }
W = { value = 30.0, unit = "mg/cm^2" }
)";

// 1-based number of the first line that starts with `needle`.
int line_in(const std::string& text, const std::string& needle) {
  auto pos = text.find(needle);
  while (pos != std::string::npos && pos > 0 && text[pos - 1] != '\n') pos = text.find(needle, pos + 1);
  EXPECT_NE(pos, std::string::npos) << needle;
  if (pos == std::string::npos) return -1;
  return 1 + static_cast<int>(std::count(text.begin(), text.begin() + pos, '\n'));
}

std::string replaced(std::string text, const std::string& from, const std::string& to) {
  const auto pos = text.find(from);
  EXPECT_NE(pos, std::string::npos) << from;
  if (pos != std::string::npos) text.replace(pos, from.size(), to);
  return text;
}

// Runs `f`, expects an InputError whose message holds every piece; `input`,
// when given, is shown if nothing is refused.
void expect_refused(const std::function<void()>& f, const std::vector<std::string>& pieces,
                    const std::string& input = "") {
  try {
    f();
    ADD_FAILURE() << "expected an InputError" << (input.empty() ? "" : " for:\n" + input);
  } catch (const InputError& e) {
    const std::string msg = e.what();
    for (const auto& p : pieces) EXPECT_NE(msg.find(p), std::string::npos) << "'" << p << "' not in: " << msg;
  }
}

// Writes `text` as a fabric, loads it, expects a refusal naming file:line and key.
void expect_file_refused(const TmpDir& dir, const std::string& text, const std::string& line_needle,
                         std::initializer_list<std::string> pieces) {
  const std::string path = dir.write("bad.toml", text);
  std::vector<std::string> all(pieces);
  all.push_back(path + ":" + std::to_string(line_in(text, line_needle)) + ":");
  expect_refused([&] { load_fabric(path); }, all, text);
}

// kGood with `from` replaced by `to`: refused as expect_file_refused expects.
void expect_edit_refused(const TmpDir& dir, const std::string& from, const std::string& to,
                         const std::string& line_needle, std::initializer_list<std::string> pieces) {
  expect_file_refused(dir, replaced(kGood, from, to), line_needle, pieces);
}

std::vector<std::string> shipped() { return list_fabrics(); }

// Composite Simpson rule over [a, b].
double simpson(const std::function<double(double)>& f, double a, double b, int n = 20000) {
  const double h = (b - a) / n;
  double s = f(a) + f(b);
  for (int i = 1; i < n; ++i) s += (i % 2 ? 4 : 2) * f(a + i * h);
  return s * h / 3;
}

// ------------------------------------------------------------ shipped data

TEST(KesShipped, ListsTheDenimsSorted) {
  const auto names = shipped();
  for (const auto& d : kDenims)
    EXPECT_NE(std::find(names.begin(), names.end(), d), names.end()) << d;
  EXPECT_NE(std::find(names.begin(), names.end(), "denim-B-synthetic"), names.end());
  EXPECT_TRUE(std::is_sorted(names.begin(), names.end()));
}

TEST(KesShipped, EveryFabricLoadsWithItsSource) {
  const auto names = shipped();
  ASSERT_GE(names.size(), 7u);
  for (const auto& n : names) {
    SCOPED_TRACE(n);
    const Fabric f = load_fabric(n);
    EXPECT_EQ(f.name, n);
    EXPECT_FALSE(f.source.empty());
    EXPECT_GT(f.density, 0);
    EXPECT_GT(f.thickness, 0);
    for (int d = 0; d < 2; ++d) {
      EXPECT_GT(f.tensile[d].emt, 0);
      EXPECT_GT(f.tensile[d].lt, 0);
      EXPECT_LE(f.tensile[d].lt, 1);
      EXPECT_GT(f.tensile[d].rt, 0);
      EXPECT_LE(f.tensile[d].rt, 1);
      EXPECT_GT(f.bending[d].b, 0);
      EXPECT_GE(f.bending[d].hb, 0);
    }
    EXPECT_GT(f.shear.g, 0);
    EXPECT_GE(f.shear.hg, 0);
  }
}

TEST(KesShipped, DenimBConvertedToSIByHand) {
  const Fabric f = load_fabric("denim-B");
  for (int d = 0; d < 2; ++d) {
    // 1 gf*cm^2/cm = 9.807e-5 N*m (KES-SOURCES.md), to 4 digits.
    EXPECT_NEAR(f.bending[d].b, 0.144 * 9.807e-5, 1e-4 * 0.144 * 9.807e-5);
    EXPECT_DOUBLE_EQ(f.bending[d].hb, 0.142 / 2 * kGf);  // HB = 2HB/2, N
    EXPECT_DOUBLE_EQ(f.tensile[d].emt, 0.05735);
    EXPECT_DOUBLE_EQ(f.tensile[d].lt, 0.655);
    EXPECT_DOUBLE_EQ(f.tensile[d].rt, 0.5239);
    EXPECT_DOUBLE_EQ(f.tensile[d].fm, 500 * kGf * 100);  // default Fm, N/m
  }
  // gf/cm/deg -> N/m per rad: times 0.9807 and 180/pi (about 56.19 N/m per rad).
  EXPECT_NEAR(f.shear.g, 1.538 * 0.980665 * 180 / kPi, 1e-9);
  EXPECT_NEAR(f.shear.g, 86.42, 0.01);
  EXPECT_DOUBLE_EQ(f.shear.hg, 3.575 / 2 * 0.980665);
  EXPECT_DOUBLE_EQ(f.thickness, 1.188e-3);
  EXPECT_NEAR(f.density, 109.32 * 1e-3, 1e-15);  // 109.32 read as g/m^2
}

// The W line of a shipped file: its number and the unit it states.
std::pair<double, std::string> weight_line(const std::string& name) {
  std::ifstream in(kes_directory() + "/" + name + ".toml");
  std::string line;
  while (std::getline(in, line)) {
    const auto v = line.find("W = { value = ");
    if (v != 0) continue;
    const auto u = line.find("unit = \"");
    const auto end = line.find('"', u + 8);
    return {std::stod(line.substr(14)), line.substr(u + 8, end - u - 8)};
  }
  ADD_FAILURE() << name << ".toml has no W line";
  return {0, ""};
}

// The weight's unit is stated in the file (g/m^2, data/kes/README.md
// "Weight"), and the loaded density follows the stated unit.
TEST(KesShipped, DenimAWeightFollowsTheStatedUnit) {
  const auto [value, unit] = weight_line("denim-A");
  EXPECT_EQ(unit, "g/m^2");
  EXPECT_EQ(value, 104);
  const double per_unit = unit == "g/m^2" ? 1e-3 : unit == "mg/cm^2" ? 1e-2 : NAN;
  EXPECT_DOUBLE_EQ(load_fabric("denim-A").density, value * per_unit);  // kg/m^2
}

// The evidence for g/m^2: each denim's bending length (B/w)^(1/3) lies in
// denim's usual 2-4 cm (read as mg/cm^2 it would be about 1.2 cm).
TEST(KesShipped, DenimBendingLengthsAreThoseOfDenim) {
  for (const auto& n : kDenims) {
    const Fabric f = load_fabric(n);
    const double w = f.density * 9.80665;  // weight per area, N/m^2
    for (int d = 0; d < 2; ++d) {
      const double c = std::cbrt(f.bending[d].b / w);
      EXPECT_GT(c, 0.02) << n;
      EXPECT_LT(c, 0.04) << n;
    }
  }
}

TEST(KesShipped, TensileBandsHaveTheKesEnergies) {
  for (const auto& n : shipped()) {
    const Fabric f = load_fabric(n);
    for (int d = 0; d < 2; ++d) {
      SCOPED_TRACE(n + (d ? " weft" : " warp"));
      const TensileKES& k = f.tensile[d];
      const Band band = Band::tensile(k);
      const double wt = k.lt * k.fm * k.emt / 2;
      const double load = simpson([&](double q) { return band.at(q).hi; }, 0, k.emt);
      const double back = simpson([&](double q) { return band.at(q).lo; }, 0, k.emt);
      EXPECT_NEAR(load, wt, 1e-6 * wt);
      EXPECT_NEAR(back, k.rt * wt, 1e-6 * k.rt * wt);
      EXPECT_NEAR(band.at(k.emt).hi, k.fm, 1e-9 * k.fm);
      for (int i = 0; i <= 3000; ++i) {
        const double q = k.emt * (-1.0 + 3.0 * i / 3000);  // compression to 2*EMT
        const BandValue v = band.at(q);
        ASSERT_LE(v.lo, v.hi) << "q = " << q;
        if (q <= 0) {
          ASSERT_EQ(v.hi, 0.0) << "tension in compression at q = " << q;
          ASSERT_EQ(v.lo, 0.0) << "tension in compression at q = " << q;
        }
      }
    }
  }
}

TEST(KesShipped, BendingAndShearBandWidthsAreTheLoopWidths) {
  for (const auto& n : shipped()) {
    SCOPED_TRACE(n);
    const Fabric f = load_fabric(n);
    for (int d = 0; d < 2; ++d) {
      const BendingKES& k = f.bending[d];
      const Band band = Band::linear(k.b, k.hb, k.load, k.unload);
      for (double kappa = -250; kappa <= 250; kappa += 12.5) {  // 1/m, the KES range
        const BandValue v = band.at(kappa);
        EXPECT_NEAR(v.hi - v.lo, 2 * k.hb, 1e-6 * k.hb) << "kappa = " << kappa;
        EXPECT_NEAR(0.5 * (v.hi + v.lo), k.b * kappa, 1e-6 * (k.hb + std::abs(k.b * kappa)));
      }
    }
    const ShearKES& s = f.shear;
    const Band band = Band::linear(s.g, s.hg, s.load, s.unload);
    for (double deg = -8; deg <= 8; deg += 0.5) {
      const double phi = deg * kPi / 180;
      const BandValue v = band.at(phi);
      EXPECT_NEAR(v.hi - v.lo, 2 * s.hg, 1e-6 * s.hg) << "phi = " << deg << " deg";
    }
  }
}

TEST(KesShipped, HalfWidthsAreHalfThePrintedLoops) {
  const Fabric a = load_fabric("denim-A");
  EXPECT_DOUBLE_EQ(a.bending[0].hb, 0.139 / 2 * kGf);
  EXPECT_DOUBLE_EQ(a.shear.hg, 5.012 / 2 * 0.980665);
  const Fabric e = load_fabric("denim-E");
  EXPECT_DOUBLE_EQ(e.bending[1].hb, 0.214 / 2 * kGf);
  EXPECT_DOUBLE_EQ(e.shear.hg, 3.575 / 2 * 0.980665);
}

// The synthesized-curve fabric samples denim-B's model: same fabric, nearly.
// Drives a band through strains qs, one time step per entry, as the time
// loop does: the anchor from the step-start force and strain, then the stop.
std::vector<double> trace(const Band& b, const std::vector<double>& qs) {
  std::vector<double> f{0.0};
  for (size_t k = 1; k < qs.size(); ++k) f.push_back(b.stop(b.anchor(f.back(), qs[k - 1]), qs[k]).f);
  return f;
}

std::vector<double> ramp(double from, double to, int n, std::vector<double> qs = {}) {
  for (int i = qs.empty() ? 0 : 1; i <= n; ++i) qs.push_back(from + (to - from) * i / n);
  return qs;
}

// In compression the band is one line of the chosen fraction of Fm/EMT, for
// the KES fit and for measured curves alike; tension is untouched by it.
TEST(BandCompression, ALineOfTheChosenModulusAndTensionUnchanged) {
  TensileKES kes;
  kes.lt = 0.62;
  kes.emt = 0.07;
  kes.rt = 0.65;
  TensileKES curve = kes;
  curve.load = {{0.0, 0.035, 0.07}, {0.0, 100.0, kes.fm}};
  curve.unload = {{0.0, 0.035, 0.07}, {0.0, 40.0, kes.fm}};
  for (const TensileKES& k : {kes, curve}) {
    const Band none = Band::tensile(k), some = Band::tensile(k, 0.1);
    const double kc = 0.1 * k.fm / k.emt, eps = Band::kCompressionOnset * k.emt;
    for (double q : {-0.2, -0.05, -1.01 * eps}) {
      const BandValue v = some.at(q);
      EXPECT_DOUBLE_EQ(v.lo, kc * (q + eps / 2));  // the line, past the onset
      EXPECT_DOUBLE_EQ(v.hi, v.lo);
      EXPECT_DOUBLE_EQ(v.dlo, kc);
      EXPECT_DOUBLE_EQ(v.dhi, kc);
      EXPECT_EQ(none.at(q).hi, 0.0);
      // A zero-width band: the hysteresis target is the line, reversal or not.
      EXPECT_DOUBLE_EQ(some.stop(some.anchor(0.0, 0.0), q).f, v.lo);
    }
    // The onset: force and slope continuous at -eps and at rest length.
    for (double q : {-eps, -1e-9}) {
      const BandValue a = some.at(q * (1 + 1e-9)), b = some.at(q * (1 - 1e-9));
      EXPECT_NEAR(a.hi, b.hi, 1e-6 * kc * eps);
      EXPECT_NEAR(a.dhi, b.dhi, 1e-6 * kc);
      EXPECT_LE(some.at(q).hi, 0.0);
    }
    EXPECT_NEAR(some.at(-1e-12).dhi, 0.0, 1e-6 * kc);
    for (double q : {1e-4, 0.03, 0.1}) {
      EXPECT_EQ(some.at(q).lo, none.at(q).lo);
      EXPECT_EQ(some.at(q).hi, none.at(q).hi);
    }
  }
}

TEST(BandReversal, SteepReversalCrossesTheBandOverTheStrainItsSlopeGives) {
  const double B = 2e-5, HB = 7e-4, K = 200, r = 5;  // denim-like bending, SI
  Band band = Band::linear(B, HB);
  band.set_reversal(r);
  std::vector<double> qs = ramp(0, K, 400);
  qs = ramp(K, -K, 800, qs);
  const std::vector<double> f = trace(band, qs);
  // Loading from rest: at r*B until the upper edge, then along it.
  const double meet = HB / ((r - 1) * B);  // where r*B*q = B*q + HB
  for (size_t k = 0; k <= 400; ++k) {
    const double q = qs[k];
    const double want = q < meet ? r * B * q : B * q + HB;
    ASSERT_NEAR(f[k], want, 1e-9 * HB) << "loading, q = " << q;
  }
  // Unloading from K: down at r*B across the band (2HB in (r-1)*B*dq), then the lower edge.
  const double across = 2 * HB / ((r - 1) * B);
  for (size_t k = 401; k < qs.size(); ++k) {
    const double dq = K - qs[k];
    const double want = dq < across ? B * K + HB - r * B * dq : B * qs[k] - HB;
    ASSERT_NEAR(f[k], want, 1e-9 * HB) << "unloading, q = " << qs[k];
  }
  // The loop is as wide as the band where both branches lie on its edges.
  EXPECT_NEAR(f[400 + 400] - (B * 0 - HB), 0.0, 1e-9 * HB);  // q = 0 on the way back
}

// Work done on the element over the strain path (trapezoids), from entry k0.
double work(const std::vector<double>& qs, const std::vector<double>& f, size_t k0) {
  double w = 0;
  for (size_t k = k0 + 1; k < qs.size(); ++k) w += 0.5 * (f[k] + f[k - 1]) * (qs[k] - qs[k - 1]);
  return w;
}

TEST(BandReversal, AClosedCycleDissipatesTheLoopsArea) {
  const double B = 2e-5, HB = 7e-4, K = 200;
  const std::vector<double> qs = ramp(-K, K, 2000, ramp(K, -K, 2000, ramp(0, K, 1000)));
  Band steep = Band::linear(B, HB);
  steep.set_reversal(5);
  // A parallelogram: 2HB high, 2K wide less the strain one reversal takes.
  const double area = 2 * HB * (2 * K - 2 * HB / (4 * B));
  EXPECT_NEAR(work(qs, trace(steep, qs), 1000), area, 1e-3 * area);
  // The band taken literally keeps the force while the strain moves, so it
  // loads along the lower edge and unloads along the upper one: the loop runs
  // backwards and each cycle gives energy to the cloth instead of taking it.
  const Band literal = Band::linear(B, HB);
  const double back = -2 * HB * (2 * K - 2 * HB / B);
  EXPECT_NEAR(work(qs, trace(literal, qs), 1000), back, 1e-3 * area);
}

TEST(BandReversal, ZeroIsTheLiteralBandAndInsideTheSplitOfStepsDoesNotMatter) {
  const double B = 2e-5, HB = 7e-4, K = 200;
  Band literal = Band::linear(B, HB);
  const std::vector<double> qs = ramp(K, K - 30, 30, ramp(0, K, 100));
  const std::vector<double> f = trace(literal, qs);
  for (size_t k = 101; k < qs.size(); ++k)  // within 2HB/B = 70 of K: the force stays put
    ASSERT_EQ(f[k], f[100]) << "q = " << qs[k];
  // With a reversal, one long step inside the band lands where many short ones do.
  TensileKES kes;
  kes.lt = 0.62;
  kes.emt = 0.07;
  kes.rt = 0.65;
  Band steep = Band::tensile(kes);
  steep.set_reversal(8);
  const double q0 = 0.05, f0 = steep.at(q0).hi;  // on the loading curve, then back a little
  const double q = q0 - 5e-4;
  const double one = steep.stop(steep.anchor(f0, q0), q).f;
  double many = f0;
  for (int i = 1; i <= 20; ++i)
    many = steep.stop(steep.anchor(many, q0 - 2.5e-5 * (i - 1)), q0 - 2.5e-5 * i).f;
  EXPECT_GT(one, steep.at(q).lo);
  EXPECT_LT(one, steep.at(q).hi);
  EXPECT_NEAR(one, many, 1e-12 * f0);
  // Its slope inside the band is reversal times the loading curve's.
  const Band::Stop st = steep.stop(steep.anchor(f0, q0), q);
  EXPECT_NEAR(st.df_dq, 8 * steep.at(q).dhi, 1e-12 * st.df_dq);
}

TEST(KesShipped, SyntheticCurvesReproduceDenimB) {
  const Fabric kes = load_fabric("denim-B");
  const Fabric crv = load_fabric("denim-B-synthetic");
  for (int d = 0; d < 2; ++d) {
    const TensileKES &a = kes.tensile[d], &b = crv.tensile[d];
    EXPECT_FALSE(b.load.empty());
    EXPECT_FALSE(b.unload.empty());
    EXPECT_NEAR(b.emt, a.emt, 1e-9);
    EXPECT_NEAR(b.fm, a.fm, 1e-9 * a.fm);
    EXPECT_NEAR(b.wt(), a.wt(), 2e-3 * a.wt());  // 40 linear segments
    EXPECT_NEAR(b.rt, a.rt, 5e-3 * a.rt);
    EXPECT_FALSE(crv.bending[d].load.empty());
    EXPECT_NEAR(crv.bending[d].b, kes.bending[d].b, 1e-6 * kes.bending[d].b);
    EXPECT_NEAR(crv.bending[d].hb, kes.bending[d].hb, 1e-6 * kes.bending[d].hb);
  }
  EXPECT_FALSE(crv.shear.load.empty());
  EXPECT_NEAR(crv.shear.g, kes.shear.g, 1e-6 * kes.shear.g);
  EXPECT_NEAR(crv.shear.hg, kes.shear.hg, 1e-6 * kes.shear.hg);
  EXPECT_DOUBLE_EQ(crv.density, kes.density);
}

// ------------------------------------------------------------ format features

TEST(KesFormat, LoadsByPathWithDirectionsAndDefaults) {
  TmpDir dir;
  const Fabric f = load_fabric(dir.write("mine.toml", kGood));
  EXPECT_EQ(f.name, "mine");
  EXPECT_EQ(f.source, "unit test");
  EXPECT_DOUBLE_EQ(f.bending[0].b, 0.18 * kGf * 1e-2);  // warp
  EXPECT_DOUBLE_EQ(f.bending[1].b, 0.16 * kGf * 1e-2);  // weft
  EXPECT_DOUBLE_EQ(f.tensile[0].fm, 500 * kGf * 100);   // Fm defaults to 500 gf/cm
  EXPECT_DOUBLE_EQ(f.density, 0.30);                    // 30 mg/cm^2
}

TEST(KesFormat, SIUnitsGiveTheSameFabric) {
  TmpDir dir;
  std::string si = kGood;
  si = replaced(si, R"(EMT = { value = 5.0, unit = "%" })", R"(EMT = { value = 0.05, unit = "1" })");
  si = replaced(si, R"(RT = { value = 50.0, unit = "%" })", R"(RT = { value = 0.5, unit = "1" })");
  si = replaced(si, R"(B = { warp = 0.18, weft = 0.16, unit = "gf*cm^2/cm" })",
                R"(B = { warp = 1.765197e-5, weft = 1.569064e-5, unit = "N*m" })");
  si = replaced(si, R"(2HB = { value = 0.14, unit = "gf*cm/cm" })",
                R"(2HB = { value = 1.372931e-3, unit = "N" })");
  si = replaced(si, R"(G = { value = 2.0, unit = "gf/cm/deg" })",
                R"(G = { value = 1.96133, unit = "N/m/deg" })");
  si = replaced(si, R"(2HG = { value = 4.0, unit = "gf/cm" })", R"(2HG = { value = 3.92266, unit = "N/m" })");
  si = replaced(si, R"(T = { value = 1.0, unit = "mm" })", R"(T = { value = 0.001, unit = "m" })");
  si = replaced(si, R"(W = { value = 30.0, unit = "mg/cm^2" })", R"(W = { value = 300, unit = "g/m^2" })");
  const Fabric a = load_fabric(dir.write("kes.toml", kGood));
  const Fabric b = load_fabric(dir.write("si.toml", si));
  for (int d = 0; d < 2; ++d) {
    EXPECT_NEAR(a.tensile[d].emt, b.tensile[d].emt, 1e-12);
    EXPECT_NEAR(a.tensile[d].rt, b.tensile[d].rt, 1e-12);
    EXPECT_NEAR(a.bending[d].b, b.bending[d].b, 1e-6 * a.bending[d].b);
    EXPECT_NEAR(a.bending[d].hb, b.bending[d].hb, 1e-6 * a.bending[d].hb);
  }
  EXPECT_NEAR(a.shear.g, b.shear.g, 1e-6 * a.shear.g);
  EXPECT_NEAR(a.shear.hg, b.shear.hg, 1e-6 * a.shear.hg);
  EXPECT_NEAR(a.thickness, b.thickness, 1e-15);
  EXPECT_NEAR(a.density, b.density, 1e-12);
}

TEST(KesFormat, ShearWarpWeftAreAveragedAndFmIsHonoured) {
  TmpDir dir;
  std::string t = replaced(kGood, R"(G = { value = 2.0, unit = "gf/cm/deg" })",
                           R"(G = { warp = 1.0, weft = 3.0, unit = "gf/cm/deg" })");
  t = replaced(t, R"(RT = { value = 50.0, unit = "%" })",
               "RT = { value = 50.0, unit = \"%\" }\nFm = { value = 490.3325, unit = \"N/m\" }");
  const Fabric f = load_fabric(dir.write("f.toml", t));
  EXPECT_NEAR(f.shear.g, 2.0 * 0.980665 * 180 / kPi, 1e-9);
  EXPECT_DOUBLE_EQ(f.tensile[1].fm, 490.3325);
}

TEST(KesFormat, WTWithinTwoPercentIsAccepted) {
  TmpDir dir;
  // LT*Fm*EMT/2 = 0.7*500*0.05/2 = 8.75 gf*cm/cm^2; 8.6 is 1.7% off.
  const std::string t = replaced(kGood, R"(RT = { value = 50.0, unit = "%" })",
                                 "RT = { value = 50.0, unit = \"%\" }\nWT = { value = 8.6, unit = \"gf*cm/cm^2\" }");
  EXPECT_NO_THROW(load_fabric(dir.write("f.toml", t)));
}

TEST(KesFormat, DrapeDataEnvironmentVariableMovesTheDirectory) {
  TmpDir dir;
  dir.write("kes/only-one.toml", kGood);
  const char* old = std::getenv("DRAPE_DATA");
  const std::string saved = old ? old : "";
  ::setenv("DRAPE_DATA", dir.path().c_str(), 1);
  EXPECT_EQ(kes_directory(), dir.path().string() + "/kes");
  EXPECT_EQ(list_fabrics(), std::vector<std::string>{"only-one"});
  EXPECT_EQ(load_fabric("only-one").name, "only-one");
  if (old)
    ::setenv("DRAPE_DATA", saved.c_str(), 1);
  else
    ::unsetenv("DRAPE_DATA");
  EXPECT_NE(kes_directory(), dir.path().string() + "/kes");
}

// ------------------------------------------------------------ refusals: values

TEST(KesRefuses, LTOutsideUnitInterval) {
  TmpDir dir;
  for (const char* v : {"1.2", "0", "-0.5"})
    expect_edit_refused(dir, "LT = { value = 0.7", std::string("LT = { value = ") + v,
                        "LT =", {"'tensile.LT'", "(0, 1]"});
}

TEST(KesRefuses, RTOutsideZeroToHundredPercent) {
  TmpDir dir;
  for (const char* v : {"120", "0", "-3"})
    expect_edit_refused(dir, "RT = { value = 50.0", std::string("RT = { value = ") + v,
                        "RT =", {"'tensile.RT'", "(0, 100]"});
}

TEST(KesRefuses, NonPositiveEMT) {
  TmpDir dir;
  expect_edit_refused(dir, "EMT = { value = 5.0", "EMT = { value = 0", "EMT =",
                      {"'tensile.EMT'", "> 0"});
}

TEST(KesRefuses, NegativeBendingRigidityNamesTheDirection) {
  TmpDir dir;
  expect_edit_refused(dir, "weft = 0.16", "weft = -0.16", "B = {",
                      {"'bending.B.weft'", "> 0", "-0.16"});
}

TEST(KesRefuses, NegativeShearRigidity) {
  TmpDir dir;
  expect_edit_refused(dir, "G = { value = 2.0", "G = { value = -2.0", "G = {",
                      {"'shear.G'", "> 0"});
}

TEST(KesRefuses, NegativeHysteresis) {
  TmpDir dir;
  expect_edit_refused(dir, "2HB = { value = 0.14", "2HB = { value = -0.14", "2HB =",
                      {"'bending.2HB'", ">= 0"});
  expect_edit_refused(dir, "2HG = { value = 4.0", "2HG = { value = -4.0", "2HG =",
                      {"'shear.2HG'", ">= 0"});
}

TEST(KesRefuses, NonPositiveThicknessOrWeight) {
  TmpDir dir;
  expect_edit_refused(dir, "T = { value = 1.0", "T = { value = 0.0", "T = {",
                      {"'physical.T'"});
  expect_edit_refused(dir, "W = { value = 30.0", "W = { value = -30.0", "W = {",
                      {"'physical.W'"});
}

TEST(KesRefuses, WTDisagreeingWithLTFmEMT) {
  TmpDir dir;
  // 8.75 expected; 9.2 is 5% off.
  const std::string t = replaced(kGood, R"(RT = { value = 50.0, unit = "%" })",
                                 "RT = { value = 50.0, unit = \"%\" }\nWT = { value = 9.2, unit = \"gf*cm/cm^2\" }");
  expect_file_refused(dir, t, "WT =", {"'tensile.WT'", "2%", "8.75"});
}

// ------------------------------------------------------------ refusals: form

TEST(KesRefuses, MissingUnit) {
  TmpDir dir;
  expect_edit_refused(dir, R"(LT = { value = 0.7, unit = "1" })", "LT = { value = 0.7 }",
                      "LT =", {"'tensile.LT'", "missing unit"});
}

TEST(KesRefuses, BareNumberWithoutUnit) {
  TmpDir dir;
  expect_edit_refused(dir, R"(LT = { value = 0.7, unit = "1" })", "LT = 0.7", "LT =",
                      {"'tensile.LT'", "unit"});
}

TEST(KesRefuses, UnknownUnitListsTheAcceptedOnes) {
  TmpDir dir;
  expect_edit_refused(dir, R"(unit = "gf*cm^2/cm")", R"(unit = "lbf*in")", "B = {",
                      {"'bending.B.unit'", "lbf*in", "gf*cm^2/cm", "N*m"});
  // A unit of the wrong dimension is unknown for that quantity.
  expect_edit_refused(dir, R"(T = { value = 1.0, unit = "mm" })",
                      R"(T = { value = 1.0, unit = "mg/cm^2" })",
                      "T = {", {"'physical.T.unit'", "\"mm\""});
}

TEST(KesRefuses, MissingRequiredKey) {
  TmpDir dir;
  expect_edit_refused(dir, "RT = { value = 50.0, unit = \"%\" }\n", "", "[tensile]",
                      {"'tensile.RT'", "missing"});
  expect_edit_refused(dir, "W = { value = 30.0, unit = \"mg/cm^2\" }\n", "", "[physical]",
                      {"'physical.W'", "missing"});
}

TEST(KesRefuses, MissingWeftOfAPerDirectionValue) {
  TmpDir dir;
  expect_edit_refused(dir, "warp = 0.18, weft = 0.16,", "warp = 0.18,", "B = {",
                      {"'bending.B.weft'", "missing"});
}

TEST(KesRefuses, MissingSection) {
  TmpDir dir;
  const std::string path =
      dir.write("bad.toml", replaced(kGood, "[source]\nreference = \"unit test\"\n", ""));
  expect_refused([&] { load_fabric(path); }, {path, "'source'", "missing"});
}

TEST(KesRefuses, UnknownKey) {
  TmpDir dir;
  expect_edit_refused(dir, "LT = {", "LTT = {", "LTT =", {"'tensile.LTT'", "unknown key"});
  expect_edit_refused(dir, "[physical]", "[phisical]", "[phisical]",
                      {"'phisical'", "unknown key"});
  expect_edit_refused(dir, "{ value = 0.7,", "{ valeu = 0.7,", "LT =",
                      {"'tensile.LT.valeu'", "unknown key"});
}

TEST(KesRefuses, WrongType) {
  TmpDir dir;
  expect_edit_refused(dir, "LT = { value = 0.7,", "LT = { value = \"0.7\",", "LT =",
                      {"'tensile.LT.value'", "expected a number", "string"});
  expect_edit_refused(dir, "reference = \"unit test\"", "reference = 42", "reference",
                      {"'source.reference'", "expected a string"});
  const std::string no_bending = replaced(
      kGood, "[bending]\nB = { warp = 0.18, weft = 0.16, unit = \"gf*cm^2/cm\" }\n2HB = { value = 0.14, unit = \"gf*cm/cm\" }\n", "");
  expect_file_refused(dir, "bending = 3\n" + no_bending, "bending = 3", {"'bending'", "expected a table"});
}

TEST(KesRefuses, TomlSyntaxErrorNamesTheLine) {
  TmpDir dir;
  expect_edit_refused(dir, "LT = { value = 0.7, unit = \"1\" }", "LT = { value = 0.7, unit = ",
                      "LT =", {"TOML syntax error"});
}

TEST(KesRefuses, UnknownFabricListsAvailableNames) {
  expect_refused([] { load_fabric("denim-Z"); }, {"unknown fabric 'denim-Z'", "available:", "denim-A", "denim-F"});
}

TEST(KesRefuses, MissingFilePath) {
  TmpDir dir;
  const std::string p = (dir.path() / "nothing.toml").string();
  expect_refused([&] { load_fabric(p); }, {p, "does not exist"});
}

// ------------------------------------------------------------ curves

const std::string kCurveToml = R"(description = "curve test"
[source]
reference = "unit test"
[tensile]
curve = "t.csv"
[bending]
B = { value = 0.15, unit = "gf*cm^2/cm" }
2HB = { value = 0.14, unit = "gf*cm/cm" }
[shear]
G = { value = 2.0, unit = "gf/cm/deg" }
2HG = { value = 4.0, unit = "gf/cm" }
[physical]
T = { value = 1.0, unit = "mm" }
W = { value = 30.0, unit = "mg/cm^2" }
)";

const std::string kCsv = R"(# a comment
branch,strain[%],tension[gf/cm]
load,0,0
load,1,20
load,2,60
unload,0,0
unload,1,5

unload,2,60
)";

// Writes the curve fabric with `csv` and expects a refusal at csv:line.
void expect_csv_refused(const TmpDir& dir, const std::string& csv, int line,
                        std::initializer_list<std::string> pieces) {
  const std::string toml = dir.write("c.toml", kCurveToml);
  const std::string path = dir.write("t.csv", csv);
  std::vector<std::string> all(pieces);
  all.push_back(line > 0 ? path + ":" + std::to_string(line) + ":" : path);
  expect_refused([&] { load_fabric(toml); }, all, csv);
}

TEST(KesCurves, CsvIsConvertedToSI) {
  TmpDir dir;
  dir.write("t.csv", kCsv);
  const Fabric f = load_fabric(dir.write("c.toml", kCurveToml));
  const TensileKES& k = f.tensile[0];
  // Strain as a fraction, tension in N/m; a zero-tension point at strain -1 is
  // put in front so that compression carries no tension.
  ASSERT_EQ(k.load.q.size(), 4u);
  EXPECT_DOUBLE_EQ(k.load.q[0], -1.0);
  EXPECT_DOUBLE_EQ(k.load.q[2], 0.01);
  EXPECT_DOUBLE_EQ(k.load.f[3], 60 * 0.980665);
  EXPECT_DOUBLE_EQ(k.emt, 0.02);
  EXPECT_DOUBLE_EQ(k.fm, 60 * 0.980665);
  // WT = area under load = (0.01*20/2 + 0.01*(20+60)/2) gf/cm = 0.5 gf/cm.
  EXPECT_NEAR(k.wt(), 0.5 * 0.980665, 1e-12);
  // Unload area = 0.01*5/2 + 0.01*65/2 = 0.35 gf/cm.
  EXPECT_NEAR(k.rt, 0.35 / 0.5, 1e-12);
  EXPECT_EQ(Band::tensile(k).at(-0.005).hi, 0.0);
}

TEST(KesCurves, MalformedRowNamesFileAndLine) {
  TmpDir dir;
  expect_csv_refused(dir, replaced(kCsv, "load,1,20", "load,1,20,7"), 4, {"3 fields"});
  expect_csv_refused(dir, replaced(kCsv, "load,1,20", "load,1,2o"), 4, {"not a finite number"});
  expect_csv_refused(dir, replaced(kCsv, "load,1,20", "lode,1,20"), 4, {"\"load\" or \"unload\""});
}

TEST(KesCurves, StrainNotRisingIsRefused) {
  TmpDir dir;
  expect_csv_refused(dir, replaced(kCsv, "unload,1,5", "unload,0,5"), 7, {"not rising", "unload"});
}

TEST(KesCurves, NoUnloadBranchIsRefused) {
  TmpDir dir;
  expect_csv_refused(dir, replaced(replaced(kCsv, "unload,0,0\nunload,1,5\n", ""), "unload,2,60\n", ""), 0,
                     {"unload branch"});
}

TEST(KesCurves, HeaderNeedsNamesAndUnits) {
  TmpDir dir;
  expect_csv_refused(dir, replaced(kCsv, "strain[%]", "strain"), 2, {"no unit"});
  expect_csv_refused(dir, replaced(kCsv, "tension[gf/cm]", "tension[lbf/in]"), 2,
                     {"unknown unit", "gf/cm"});
  expect_csv_refused(dir, replaced(kCsv, "strain[%]", "curvature[1/cm]"), 2, {"strain"});
}

TEST(KesCurves, PhysicallyImpossibleTensileCurvesAreRefused) {
  TmpDir dir;
  expect_csv_refused(dir, replaced(kCsv, "unload,1,5", "unload,1,30"), 7, {"above the load branch"});
  expect_csv_refused(dir, replaced(kCsv, "load,0,0", "load,0,3"), 3, {"zero tension"});
}

TEST(KesCurves, CurveAndKesValuesTogetherAreRefused) {
  TmpDir dir;
  dir.write("t.csv", kCsv);
  const std::string t = replaced(kCurveToml, "curve = \"t.csv\"", "curve = \"t.csv\"\nLT = { value = 0.7, unit = \"1\" }");
  expect_file_refused(dir, t, "LT =", {"'tensile.LT'", "either"});
}

TEST(KesCurves, MissingCurveFileIsRefused) {
  TmpDir dir;
  expect_file_refused(dir, kCurveToml, "curve =", {"'tensile.curve'", "t.csv", "does not exist"});
}

}  // namespace
}  // namespace drape
