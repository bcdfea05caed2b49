// Small plane-geometry helpers for polygons given as coordinate arrays (counter-clockwise).
#pragma once

#include <cmath>
#include <cstddef>
#include <vector>

namespace mesopen {

struct Point {
  double x, y;
};

inline double cross(double ax, double ay, double bx, double by) { return ax * by - ay * bx; }

// Signed area (shoelace formula), positive for counter-clockwise order.
double signedArea(const double *x, const double *y, std::size_t n);

// Centroid of a simple polygon (area-weighted).
Point centroid(const double *x, const double *y, std::size_t n);

// True when every turn is to the left (or straight within `tolerance` of the edge lengths).
bool isConvex(const double *x, const double *y, std::size_t n, double tolerance = 1e-12);

// Equivalent diameter D = sqrt(4A/pi) (thesis section 4.2.4).
inline double equivalentDiameter(double area) { return std::sqrt(4.0 * area / M_PI); }

// Area of the part of a convex polygon inside the axis-aligned rectangle (Sutherland-Hodgman).
double clippedArea(const double *x, const double *y, std::size_t n, double x0, double y0, double x1,
                   double y1);

} // namespace mesopen
