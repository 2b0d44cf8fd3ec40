#include "tests/ReferenceSvd.h"

#include <Eigen/SVD>

namespace osgBTF::test {

Eigen::VectorXd referenceSingularValues(const Eigen::MatrixXd& a) {
    return Eigen::JacobiSVD<Eigen::MatrixXd>(a).singularValues();
}

}  // namespace osgBTF::test
