// A binocular observer with human limits (docs/runner.md, "The human
// observer"), beside the ideal geometer of perception.hpp. Both start from
// the same sight lines (perception.hpp, sight_lines); they differ in what the
// visual system makes of them:
//  - vergence: the eyes fixate one point of the judged shape, within what
//    they can reach (a divergence limit beyond parallel, a near point); the
//    distance read from that vergence is pulled toward a resting "specific
//    distance" by a weighted mean in dioptres (Foley 1980, Psychological
//    Review 87:411; Gogel & Tietz 1973; Tresilian, Mon-Williams & Kelly
//    1999, Proc. R. Soc. B 266:39), finite for parallel and slightly
//    diverging eyes;
//  - shape: the other points are placed by their disparity relative to the
//    fixated one, scaled by that perceived distance — every sight-line pair
//    turned by the same vergence offset, so that the fixated point reads at
//    the perceived distance, and then met. Depth is overestimated nearer
//    than the specific distance and underestimated beyond it (Johnston 1991,
//    Vision Research 31:1351);
//  - noise in disparity: a stereo threshold in arcseconds that rises with
//    the pedestal, the fixated point's residual disparity when the eyes
//    cannot verge on it (Blakemore 1970; McKee, Levi & Bowne 1990);
//  - fusion: the observer looks along the shape, fixating each point in
//    turn, so a point is seen double only when the eyes cannot verge on it
//    (beyond the divergence limit or the near point) by more than the
//    fusional limit of the fovea (Panum's area; Ogle 1950).
// Everything is in the nose frame (perception.hpp): x right, y up, −z forward.
#pragma once

#include "curvlab/geometry/perception.hpp"

#include <array>
#include <cstddef>
#include <vector>

namespace curvlab::geometry {

// One observer's limits. Defaults and their sources: docs/runner.md.
struct HumanVision {
  // Weight of the vergence-specified distance against the specific
  // distance, both in dioptres: 1/D' = w/D + (1 − w)/D_s.
  double vergence_weight = 0.5;
  double specific_distance_m = 1.0;
  // Disparity noise SD at zero pedestal (d′ = 1), arcseconds, and its rise
  // per unit of pedestal disparity (a Weber fraction).
  double threshold_arcsec = 30.0;
  double pedestal_fraction = 0.05;
  // Fusional limit at the fovea (arcminutes).
  double fusion_arcmin = 20.0;
  // How far the eyes can diverge beyond parallel, and converge (degrees).
  double divergence_limit_deg = 1.0;
  double convergence_limit_deg = 35.0;
};

// The horizontal disparity of a sight-line pair: the left eye's yaw toward
// its line minus the right eye's, in the plane of the eyes' axis and the
// forward direction (positive converging): the vergence the point demands.
double vergence_of(const EyeOffsets& eyes, const std::array<SightLine, 2>& lines);

// Where the eyes are pointed and what distance they signal.
struct Fixation {
  double demand_rad = 0.0;    // the vergence the fixated point asks for
  double achieved_rad = 0.0;  // clamped to [−divergence, convergence] limits
  double pedestal_rad = 0.0;  // demand − achieved: the fixated point's residual disparity
  double perceived_rad = 0.0; // the vergence the perceived distance stands for
  double perceived_distance_m = 0.0;
};
Fixation fixate(const HumanVision& v, double demand_rad, double ipd_m);

// A sight-line pair as perceived under `f`: each eye's line turned about the
// eyes' up axis by half the offset between the perceived and achieved
// vergence (the left inward, the right outward, or both the other way), and
// the two met (closest_approach's midpoint).
Vec3 perceive_with(const Fixation& f, const EyeOffsets& eyes, const std::array<SightLine, 2>& lines);

// The part of a vergence demand beyond the eyes' reach (0 within it), and
// the stereo threshold at a pedestal disparity (radians).
double beyond_reach_rad(const HumanVision& v, double demand_rad);
double stereo_threshold_rad(const HumanVision& v, double pedestal_rad);
// The depth one radian of relative disparity signals at the perceived
// fixation distance: −d/dγ of (ipd/2)/tan(γ/2) = (ipd/4)/sin²(γ/2).
double depth_per_disparity_m(const Fixation& f, double ipd_m);

// A judged shape (the stick's ends and middle, the table's rim and centre)
// as the human observer perceives it while fixating one of its points.
struct HumanPercept {
  std::vector<Vec3> points_m;  // perceived, in the order given
  Fixation fixation;
  // Fused unless the eyes miss some point by more than the fusional limit
  // (beyond_reach over fusion_arcmin: worst_fusion, > 1 seen double).
  bool fused = true;
  double worst_fusion = 0.0;
  double threshold_rad = 0.0;          // noise SD of a relative disparity
  double depth_per_disparity_m = 0.0;  // metres of perceived depth per radian
};
HumanPercept perceive_human(const HumanVision& v, const EyeOffsets& eyes,
                            const std::vector<std::array<SightLine, 2>>& lines, std::size_t fixated);

// The same for points of the space seen from `nose` in a view preset
// (sight_lines of each, then perceive_human).
HumanPercept perceive_human_at(const Space& space, const Isometry& nose, const EyeOffsets& eyes, ViewPreset preset,
                               const std::vector<Point>& points, std::size_t fixated, const HumanVision& v);

// A horizontal stick straight ahead (as perceive_stick): the human
// observer's perceived sagitta while fixating its middle.
struct HumanStickPerception {
  HumanPercept percept;
  double perceived_sagitta_m = 0.0;  // 0 when monocular
};
HumanStickPerception perceive_stick_human(const Space& space, const BentStick& stick, double distance_m,
                                          const EyeOffsets& eyes, ViewPreset preset, const HumanVision& v);

}  // namespace curvlab::geometry
