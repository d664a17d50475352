// Anatomy of the procedural body: anthropometric joint placement and the
// girth profile of every body part, as functions of the shape parameters.
//
// Segment lengths are fractions of stature H from Drillis & Contini (1966) as
// tabulated by Winter, "Biomechanics and Motor Control of Human Movement"
// (4th ed., fig. 4.1): ankle height 0.039H, knee 0.285H, hip 0.530H (greater
// trochanter; the joint centre sits ~0.04H lower), shoulder 0.818H, chin
// 0.870H, upper arm 0.186H, forearm 0.146H, hand 0.108H, foot length 0.152H,
// hip width 0.191H, shoulder width 0.259H. Arm lengths are shortened by ~8 %
// so that the arm span is ≈ 1.04 H as measured on adults (the Winter fractions
// are bone-end to bone-end and overlap at the joints). Girths are those of an
// average adult (thigh ≈ 55 cm, calf ≈ 37 cm, upper arm ≈ 31 cm, wrist ≈ 17 cm,
// waist ≈ 80 cm, chest ≈ 95 cm, hips ≈ 98 cm) turned into ellipse radii
// (the smooth union adds ~1 cm of radius where two parts overlap).
#include <cmath>

#include "body/procedural_body_internal.hpp"
#include "sflsh/core/error.hpp"

namespace sflsh::procedural {
namespace {

constexpr double H = kBaseStature;

/// Overall scale for β0 (uniform about the origin, so the feet stay on y = 0).
double size_scale(const BodyParams& p) { return 1.0 + kStaturePerUnit * p.stature; }

/// Landmarks of the body at base size (before the β0 scaling).
Landmarks base_landmarks(const BodyParams& p) {
  const double leg = 1.0 + 0.03 * p.leg_length;   // thigh + shank, 3 % per unit
  const double arm = 1.0 + 0.03 * p.arm_length;   // upper arm + forearm, 3 % per unit
  const double shoulder_out = 0.010 * p.shoulder_width;  // metres per side per unit
  Landmarks L;
  const double ankle_y = 0.039 * H;
  const double knee_y = ankle_y + 0.246 * H * leg;
  const double hip_y = knee_y + 0.205 * H * leg;
  const double lift = hip_y - 0.49 * H;  // the trunk rides on the legs
  auto trunk = [&](double fraction, double z) { return Vec3(0.0, fraction * H + lift, z); };
  L[0] = trunk(0.535, 0.0);      // pelvis: between the hip joints, ~8 cm above them
  L[3] = trunk(0.597, -0.010);   // spine1: lumbar L3-L4
  L[6] = trunk(0.668, -0.005);   // spine2: thoracolumbar T12
  L[9] = trunk(0.697, 0.000);    // spine3: mid-thoracic, chest level
  L[12] = trunk(0.820, -0.015);  // neck: C7, shoulder height
  L[15] = trunk(0.870, 0.010);   // head: atlanto-occipital, chin height
  L[kHeadTop] = trunk(1.0, 0.0);
  for (int side = 0; side < 2; ++side) {
    const double s = side == 0 ? 1.0 : -1.0;  // SMPL's left is +X
    L[1 + side] = Vec3(s * 0.050 * H, hip_y, 0.0);                  // hip joint centre
    L[4 + side] = Vec3(s * 0.060 * H, knee_y, 0.005);               // knee
    L[7 + side] = Vec3(s * 0.065 * H, ankle_y, -0.010);             // ankle (malleoli)
    L[10 + side] = Vec3(s * (0.065 * H + 0.012), 0.016 * H, 0.125); // foot: ball of the foot
    L[kLeftToeTip + side] = Vec3(s * (0.065 * H + 0.018), 0.012 * H, 0.200);
    L[13 + side] = Vec3(s * 0.040 * H, 0.790 * H + lift, -0.005);   // collar (sternoclavicular)
    const Vec3 shoulder(s * (0.098 * H + shoulder_out), 0.800 * H + lift, -0.010);
    L[16 + side] = shoulder;                                        // glenohumeral joint
    L[18 + side] = shoulder + Vec3(s * 0.170 * H * arm, 0.0, -0.005);     // elbow
    L[20 + side] = L[18 + side] + Vec3(s * 0.145 * H * arm, 0.0, 0.005);  // wrist
    L[22 + side] = L[20 + side] + Vec3(s * 0.050 * H, 0.0, 0.0);          // hand: knuckles
    L[kLeftFingertip + side] = L[20 + side] + Vec3(s * 0.105 * H, 0.0, 0.0);
  }
  return L;
}

/// A tapered elliptic capsule (see Primitive).
Primitive capsule(const Vec3& a, const Vec3& b, const Vec3& e1, double r1a, double r2a, double r1b, double r2b,
                  double cap_a, double cap_b) {
  return Primitive{a, b, e1, r1a, r2a, r1b, r2b, cap_a, cap_b};
}

}  // namespace

void BodyParams::add(int index, double amount) {
  double* fields[kNumShapeParameters] = {&stature, &girth,      &muscle,     &chest,          &waist,
                                         &hips,    &arm_length, &leg_length, &shoulder_width, &belly};
  require(index >= 0 && index < kNumShapeParameters, "procedural body: shape parameter ", index,
          " out of range, expected 0..", kNumShapeParameters - 1);
  *fields[index] += amount;
}

const std::array<std::string, kNumShapeParameters>& shape_parameter_meanings() {
  static const std::array<std::string, kNumShapeParameters> meanings = {
      "overall size: +1 = 3.2% taller and larger (about +5.6 cm stature), uniform scale about the floor point",
      "weight/girth: +1 = torso and limb girths +5%",
      "muscle: +1 = upper arm, forearm, thigh, calf, shoulder and chest girths +2.5..3.5%",
      "chest: +1 = chest width +3.5%, depth +4.5%",
      "waist: +1 = waist width and depth +5%",
      "hips/buttocks: +1 = hip width +4%, buttocks +6%",
      "arm length: +1 = upper arm and forearm 3% longer",
      "leg length: +1 = thigh and shank 3% longer (the trunk rises with them)",
      "shoulder width: +1 = shoulder joints 1.0 cm further out on each side",
      "belly: +1 = belly 8% deeper and 0.8 cm further forward"};
  return meanings;
}

Landmarks make_landmarks(const BodyParams& params) {
  Landmarks L = base_landmarks(params);
  const double scale = size_scale(params);
  for (Vec3& x : L) x *= scale;
  return L;
}

std::vector<Primitive> make_primitives(const BodyParams& p) {
  const Landmarks L = base_landmarks(p);
  const double lift = L[1].y() - 0.49 * H;
  auto trunk = [&](double fraction, double z) { return Vec3(0.0, fraction * H + lift, z); };
  const Vec3 X = Vec3::UnitX(), Y = Vec3::UnitY();

  // Relative girth changes per body region (see shape_parameter_meanings).
  const double girth = 1.0 + 0.05 * p.girth;
  const double limb = girth * (1.0 + 0.035 * p.muscle);
  const double forearm = girth * (1.0 + 0.025 * p.muscle);
  const double extremity = 1.0 + 0.015 * p.girth;  // hands and feet barely fatten
  const double head = 1.0 + 0.01 * p.girth;
  const double neck = 1.0 + 0.04 * p.girth + 0.02 * p.muscle;
  const double chest_w = girth * (1.0 + 0.02 * p.muscle) * (1.0 + 0.035 * p.chest);
  const double chest_d = girth * (1.0 + 0.02 * p.muscle) * (1.0 + 0.045 * p.chest);
  const double waist = girth * (1.0 + 0.05 * p.waist);
  const double hip_w = girth * (1.0 + 0.04 * p.hips);
  const double hip_d = girth * (1.0 + 0.03 * p.hips);
  const double buttock = girth * (1.0 + 0.06 * p.hips);
  const double girdle = girth * (1.0 + 0.03 * p.muscle);
  const double belly_d = girth * (1.0 + 0.08 * p.belly);
  const double belly_w = girth * (1.0 + 0.04 * p.belly);

  std::vector<Primitive> prims;
  // Trunk (cross-section axis e1 = X: width, e2 = Z: depth).
  prims.push_back(capsule(trunk(0.500, -0.005), trunk(0.560, -0.005), X, 0.166 * hip_w, 0.102 * hip_d,
                          0.150 * hip_w, 0.092 * hip_d, 0.060, 0.050));  // pelvis block
  prims.push_back(capsule(trunk(0.560, -0.005), trunk(0.645, 0.0), X, 0.138 * waist, 0.090 * waist, 0.140 * waist,
                          0.095 * waist, 0.050, 0.050));  // waist
  prims.push_back(capsule(trunk(0.645, 0.0), trunk(0.745, 0.0), X, 0.155 * chest_w, 0.108 * chest_d,
                          0.168 * chest_w, 0.112 * chest_d, 0.050, 0.060));  // chest
  prims.push_back(capsule(trunk(0.575, 0.030 + 0.008 * p.belly), trunk(0.605, 0.030 + 0.008 * p.belly), X,
                          0.110 * belly_w, 0.070 * belly_d, 0.110 * belly_w, 0.070 * belly_d, 0.060, 0.060));  // belly
  prims.push_back(capsule(trunk(0.780, -0.010), trunk(0.885, 0.005), X, 0.058 * neck, 0.062 * neck, 0.052 * neck,
                          0.055 * neck, 0.030, 0.030));  // neck
  {
    const double yc = H + lift - 0.118;  // head: ellipsoid reaching the stature
    prims.push_back(capsule(Vec3(0, yc - 0.020, 0.010), Vec3(0, yc + 0.020, 0.010), X, 0.075 * head, 0.095 * head,
                            0.075 * head, 0.095 * head, 0.098, 0.098));
    prims.push_back(capsule(trunk(0.897, 0.030), trunk(0.910, 0.040), X, 0.052 * head, 0.055 * head, 0.052 * head,
                            0.055 * head, 0.035, 0.035));  // jaw and face
  }
  // Buttocks: one body across both sides, so that growing it never folds a
  // cleft between two blobs.
  prims.push_back(capsule(Vec3(0.060, 0.505 * H + lift, -0.050), Vec3(-0.060, 0.505 * H + lift, -0.050), Y,
                          0.075 * buttock, 0.070 * buttock, 0.075 * buttock, 0.070 * buttock, 0.070 * buttock,
                          0.070 * buttock));
  for (int side = 0; side < 2; ++side) {
    const double s = side == 0 ? 1.0 : -1.0;
    // Shoulder girdle: trapezius and deltoid from the spine to the shoulder.
    prims.push_back(capsule(Vec3(0.0, 0.775 * H + lift, -0.010), L[16 + side] + Vec3(0, -0.008 * H, -0.002), Y,
                            0.070 * girdle, 0.085 * girdle, 0.055 * girdle, 0.055 * girdle, 0.040, 0.050));
    // Arm (e1 = Y: thickness, e2 = Z: width), mitten hand.
    const Vec3 shoulder = L[16 + side], elbow = L[18 + side], wrist = L[20 + side], knuckles = L[22 + side];
    prims.push_back(capsule(shoulder, elbow, Y, 0.050 * limb, 0.052 * limb, 0.040 * limb, 0.042 * limb, 0.050, 0.040));
    prims.push_back(capsule(elbow, wrist, Y, 0.040 * forearm, 0.043 * forearm, 0.024 * forearm, 0.031 * forearm, 0.040,
                            0.024));
    prims.push_back(capsule(wrist, knuckles, Y, 0.020 * extremity, 0.036 * extremity, 0.018 * extremity,
                            0.044 * extremity, 0.020, 0.018));  // palm
    prims.push_back(capsule(knuckles, L[kLeftFingertip + side] - Vec3(s * 0.020, 0, 0), Y, 0.017 * extremity,
                            0.044 * extremity, 0.014 * extremity, 0.038 * extremity, 0.017, 0.020));  // fingers
    // Leg (e1 = X: width, e2 = Z: depth).
    const Vec3 hip = L[1 + side], knee = L[4 + side], ankle = L[7 + side];
    // Thigh. Its top grows outwards only (the axis moves out by the change of
    // radius), keeping the inner thighs where they are: otherwise girth would
    // push the two inner thighs into each other at the crotch.
    const double thigh_top = limb * (1.0 + 0.02 * p.hips);
    const Vec3 thigh_start = hip + Vec3(s * 0.080 * (thigh_top - 1.0), 0, 0);
    prims.push_back(capsule(thigh_start, knee, X, 0.080 * thigh_top, 0.088 * thigh_top, 0.052 * limb, 0.055 * limb,
                            0.080, 0.050));
    const Vec3 calf = knee + 0.3 * (ankle - knee) + Vec3(0, 0, -0.015);
    prims.push_back(capsule(knee, calf, X, 0.047 * limb, 0.049 * limb, 0.048 * limb, 0.055 * limb, 0.040, 0.040));
    prims.push_back(capsule(calf, ankle, X, 0.048 * limb, 0.055 * limb, 0.030 * limb, 0.033 * limb, 0.040, 0.030));
    // Foot: heel to ball, then toes (e1 = X: width, e2 ≈ Y: height); sole on y = 0.
    const Vec3 heel(ankle.x(), 0.038, -0.050), ball = L[10 + side];
    prims.push_back(capsule(heel, ball, X, 0.032 * extremity, 0.038, 0.045 * extremity, 0.028, 0.030, 0.020));
    prims.push_back(capsule(ball, L[kLeftToeTip + side] - Vec3(0, 0, 0.020), X, 0.045 * extremity, 0.026,
                            0.035 * extremity, 0.018, 0.020, 0.020));
  }
  const double scale = size_scale(p);
  for (Primitive& q : prims) {
    q.a *= scale;
    q.b *= scale;
    q.r1a *= scale, q.r2a *= scale, q.r1b *= scale, q.r2b *= scale, q.cap_a *= scale, q.cap_b *= scale;
  }
  return prims;
}

const std::vector<WeightSegment>& weight_segments() {
  // Joint j carries the part that rotates with it: the bone from j to its
  // child (SMPL's convention); the pelvis also carries the hip girdle.
  static const std::vector<WeightSegment> segments = {
      {0, 0, 3},   {0, 1, 2},   {1, 1, 4},   {2, 2, 5},   {3, 3, 6},   {4, 4, 7},
      {5, 5, 8},   {6, 6, 9},   {7, 7, 10},  {8, 8, 11},  {9, 9, 12},  {10, 10, kLeftToeTip},
      {11, 11, kRightToeTip}, {12, 12, 15}, {13, 13, 16}, {14, 14, 17}, {15, 15, kHeadTop},
      {16, 16, 18}, {17, 17, 19}, {18, 18, 20}, {19, 19, 21}, {20, 20, 22}, {21, 21, 23},
      {22, 22, kLeftFingertip}, {23, 23, kRightFingertip}};
  return segments;
}

}  // namespace sflsh::procedural
