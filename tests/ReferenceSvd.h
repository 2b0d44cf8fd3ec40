// The direct SVD that the low-rank tests (pca, lpca, fmf) measure the fits against (Eckart-Young).
// One non-template function in its own translation unit: Eigen's SVDs are the most expensive code
// to compile in the tests (JacobiSVD ~20 s, BDCSVD ~65 s per translation unit under the
// sanitizers), so they are instantiated once, and that unit keeps the build type's optimisation
// when the tests are compiled with a lower one (OSGBTF_TEST_OPTIMIZE, tests/CMakeLists.txt).
#pragma once

#include <Eigen/Core>

namespace osgBTF::test {

/** All min(rows, cols) singular values of `a`, descending, by Eigen's two-sided Jacobi SVD: the
 *  most accurate direct SVD (relative accuracy), and on the tests' tall 19683 x 256 ABRDF matrix
 *  also faster than BDCSVD (its QR preconditioner reduces it to 256 x 256 first). */
Eigen::VectorXd referenceSingularValues(const Eigen::MatrixXd& a);

}  // namespace osgBTF::test
