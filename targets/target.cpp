#include "target.hpp"

namespace mesopen {

void Polygons::add(const std::vector<double> &px, const std::vector<double> &py) {
  x.insert(x.end(), px.begin(), px.end());
  y.insert(y.end(), py.begin(), py.end());
  offset.push_back(x.size());
}

} // namespace mesopen
