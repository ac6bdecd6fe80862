// Reference values computed by an independent Python prototype of the method (numpy/scipy,
// docs/validation.md), printed with 12 decimals: compared to 1e-11 absolute.
#include <gtest/gtest.h>

#include "lie/lie_test_util.h"
#include "screwfem/lie/se3.h"

namespace screwfem::se3_vectors_test {
namespace {

using test::MatrixNear;

constexpr double kPrinted = 1e-11;  // the printed digits

Vec6 VectorXi() {
  Vec6 xi;
  xi << 0.1, -0.2, 0.3, 0.4, -0.5, 0.6;
  return xi;
}

TEST(Se3TestVectors, ExpSE3MatchesPrototypeValues) {
  Mat4 expected;
  expected << 0.714075363402, -0.619656510510, -0.325764001026, 0.094116818494,  //
      0.432164945528, 0.756260965523, -0.491225825749, -0.229085933085,          //
      0.550753879005, 0.209988478276, 0.807821145893, 0.279683843433,            //
      0.0, 0.0, 0.0, 1.0;
  EXPECT_TRUE(MatrixNear(ExpSE3(VectorXi()).Matrix(), expected, kPrinted));
}

TEST(Se3TestVectors, TSE3MatchesPrototypeValues) {
  Mat6 expected = Mat6::Zero();
  expected.topRows<3>() << 0.902176502363, 0.249164069559, 0.272852389724, -0.086669237872,
      0.105603805409, 0.108715074353,  //
      -0.313310625387, 0.916609477424, 0.139381648111, -0.145242712410, -0.067887950838,
      -0.005014044775,  //
      -0.195876522731, -0.235601481853, 0.934249780276, -0.053450799251, -0.078499274163,
      -0.042794825936;
  expected.bottomRightCorner<3, 3>() = expected.topLeftCorner<3, 3>();
  EXPECT_TRUE(MatrixNear(TSE3(VectorXi()), expected, kPrinted));
}

TEST(Se3TestVectors, TSE3InvMatchesPrototypeValues) {
  Mat6 expected = Mat6::Zero();
  expected.topRows<3>() << 0.948502110807, -0.316884553834, -0.229738535400, -0.047839443771,
      -0.161159449512, -0.084582514126,  //
      0.283115446166, 0.956100160032, -0.225326830751, 0.138840550488, -0.037625691186,
      -0.073070881956,  //
      0.270261464600, 0.174673169249, 0.965386664641, 0.115417485874, 0.026929118044,
      -0.024016578883;
  expected.bottomRightCorner<3, 3>() = expected.topLeftCorner<3, 3>();
  EXPECT_TRUE(MatrixNear(TSE3Inv(VectorXi()), expected, kPrinted));
}

TEST(Se3TestVectors, DTSE3InvTMatchesPrototypeValues) {
  Vec6 sigma;
  sigma << 1.0, 2.0, 3.0, 4.0, 5.0, 6.0;
  Mat6 expected;
  expected << 0, 0, 0, 0.067203828080, -1.347621031427, 0.999498419117,  //
      0, 0, 0, 1.320244637415, 0.188814526335, -0.832950120755,          //
      0, 0, 0, -1.153794349110, 0.856867336266, -0.053403708410,         //
      0.067203828080, -1.347621031427, 0.999498419117, 0.133091406266, -2.437682892090,
      2.267848654298,  //
      1.320244637415, 0.188814526335, -0.832950120755, 2.432084400311, 0.536898447710,
      -2.929471057735,  //
      -1.153794349110, 0.856867336266, -0.053403708410, -2.734960149058, 2.922681776084,
      -0.110585703222;
  EXPECT_TRUE(MatrixNear(DTSE3InvT(VectorXi(), sigma), expected, kPrinted));
}

TEST(Se3TestVectors, LogSE3NearPiMatchesPrototypeValues) {
  SE3 H;
  H.R = ExpSO3(Vec3(0.0, 0.0, test::kPi - 1e-9));
  H.x = Vec3(1.0, 2.0, 3.0);
  Vec6 expected;
  expected << 3.141592653375, -1.570796324724, 3.0, 0.0, 0.0, 3.14159265259;
  // The last entry is printed with 11 decimals only.
  EXPECT_TRUE(MatrixNear(LogSE3(H), expected, 1e-11));
  EXPECT_NEAR(LogSE3(H)(5), test::kPi - 1e-9, 1e-15);
}

}  // namespace
}  // namespace screwfem::se3_vectors_test
