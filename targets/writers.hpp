// Files a target is written to (ARCHITECTURE.md): target.h5 (everything), target.data
// (LIGGGHTS 2D granular data file), target.vtu (ParaView), a YADE sphere list. Every file is
// written to a temporary name beside its destination and renamed when complete, so a file is
// either whole or absent. HDF5 files carry no time stamps: the same target gives the same bytes.
#pragma once

#include "disks.hpp"
#include "projectile.hpp"
#include "target.hpp"

#include <string>

class vtkUnstructuredGrid;

namespace mesopen {

// target.h5 layout (all float64 in metres unless said):
//   attributes of /: format = "mesopen-target", version, width, height, seed, porosity_requested,
//                    diameter_min, diameter_max, void_ratio, mesh_size, density
//   /sites/{x,y,r}, attribute grains (grain sites first, void sites after)
//   /grains/{offset (uint64, n+1), x, y, site (uint32), area, diameter, centroid_x, centroid_y}
//   /mesh/{node_offset, tri_offset (uint64), x, y, tri (uint32, triangles x 3)}  when meshed
//   /projectile/{outline_x, outline_y, x, y, tri} with attributes diameter, length, crh,
//                nose_length, tip_cut, offset_x, offset_y                       when enabled
void writeTargetH5(const std::string &path, const Target &target,
                   const PlacedProjectile *projectile);

// LIGGGHTS data file for atom_style granular in 2D: `disks` (as targetDisks makes them: at the
// centroids, of the grains' masses per metre rho A, touching but not overlapping each other, the
// walls or the FE bodies) in the target's box. Columns: id type diameter density x y z.
void writeLiggghtsData(const std::string &path, const Target &target, const Disks &disks);

// ParaView: grain polygons (or their triangles when meshed) and the projectile, with cell data
// body (0 projectile, 1.. grains), grain diameter.
void writeTargetVtu(const std::string &path, const Target &target,
                    const PlacedProjectile *projectile);

// YADE sphere list: one line "x y z r density" per disk (z = 0), the disks of the LIGGGHTS file,
// so that no two overlap; yade.ymport.text reads the first four columns.
void writeYadeSpheres(const std::string &path, const Disks &disks);

// An unstructured grid as a binary appended .vtu file (uncompressed), written atomically.
void writeVtu(const std::string &path, vtkUnstructuredGrid *grid);

} // namespace mesopen
