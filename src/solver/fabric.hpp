#pragma once
// A fabric's mechanical data in SI units, as read from data/kes/ by
// src/io/kes.cpp. Stretch, bending and shear each come either from KES
// characteristic values or from measured loading/unloading curves.
#include <string>
#include <vector>

namespace drape {

// A measured curve: abscissa q (strain, curvature 1/m, shear angle rad),
// ordinate f (tension N/m, moment N*m/m, shear force N/m); q strictly rising.
struct Curve {
  std::vector<double> q, f;
  bool empty() const { return q.empty(); }
};

// KES tensile test (KES-FB1) for one direction.
struct TensileKES {
  double emt = 0.05;  // strain at Fm (EMT/100)
  double lt = 0.7;    // linearity, (0, 1]
  double rt = 0.5;    // resilience, (0, 1] (RT/100)
  double fm = 490.3;  // N/m, maximum load of the test (500 gf/cm)
  double wt() const { return lt * fm * emt / 2.0; }  // J/m^2, energy to Fm
  Curve load, unload;  // measured curves; when set they replace the KES fit
};

// KES bending (KES-FB2) for one direction: |M - B*kappa| <= HB.
struct BendingKES {
  double b = 1.5e-5;   // N*m (per unit width: N*m^2/m)
  double hb = 7e-4;    // N (half loop width 2HB/2, N*m/m)
  Curve load, unload;  // measured, optional
};

// KES shear: |S - G*phi| <= HG.
struct ShearKES {
  double g = 100.0;    // N/m per rad
  double hg = 2.0;     // N/m (half of 2HG)
  Curve load, unload;  // measured, optional
};

struct Fabric {
  std::string name;
  std::string source;       // bibliographic source of the numbers
  double density = 0.3;     // kg/m^2 (KES W)
  double thickness = 1e-3;  // m (KES T)
  TensileKES tensile[2];    // [0] warp (i), [1] weft (j)
  BendingKES bending[2];
  ShearKES shear;
};

}  // namespace drape
