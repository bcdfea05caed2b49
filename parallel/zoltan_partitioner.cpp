#include "zoltan_partitioner.hpp"

#include "mpi_communicator.hpp"

#include <zoltan.h>

#include <algorithm>
#include <stdexcept>
#include <string>

namespace mesopen::parallel {

namespace {

// Zoltan's global ids are ZOLTAN_ID_TYPE, unsigned int in Debian's build: one entry holds an id
// below 2^32, which PartitionItems promises.
static_assert(sizeof(ZOLTAN_ID_TYPE) >= sizeof(std::uint32_t));

// The callbacks through which Zoltan reads this process's items.
int itemCount(void *data, int *error) {
  *error = ZOLTAN_OK;
  return static_cast<int>(static_cast<const PartitionItems *>(data)->size());
}

void itemList(void *data, int /*gid_entries*/, int /*lid_entries*/, ZOLTAN_ID_PTR global_ids,
              ZOLTAN_ID_PTR local_ids, int /*weight_dim*/, float *weights, int *error) {
  const auto &items = *static_cast<const PartitionItems *>(data);
  for (std::size_t k = 0; k < items.size(); ++k) {
    global_ids[k] = items.id[k];
    local_ids[k] = static_cast<ZOLTAN_ID_TYPE>(k);
    weights[k] = static_cast<float>(items.weight[k]);
  }
  *error = ZOLTAN_OK;
}

int dimensions(void *, int *error) {
  *error = ZOLTAN_OK;
  return 2;
}

void points(void *data, int /*gid_entries*/, int /*lid_entries*/, int count,
            ZOLTAN_ID_PTR /*global_ids*/, ZOLTAN_ID_PTR local_ids, int /*dims*/, double *xy,
            int *error) {
  const auto &items = *static_cast<const PartitionItems *>(data);
  for (int k = 0; k < count; ++k) {
    xy[2 * k] = items.x[local_ids[k]];
    xy[2 * k + 1] = items.y[local_ids[k]];
  }
  *error = ZOLTAN_OK;
}

} // namespace

ZoltanRcb::ZoltanRcb(MPI_Comm comm) : comm_(comm) {
  float version = 0.0f;
  if (Zoltan_Initialize(0, nullptr, &version) != ZOLTAN_OK)
    throw std::runtime_error("Zoltan_Initialize failed");
  zoltan_ = Zoltan_Create(comm);
  if (!zoltan_)
    throw std::runtime_error("Zoltan_Create failed");
  const char *settings[][2] = {
      {"DEBUG_LEVEL", "0"},         // silent
      {"LB_METHOD", "RCB"},         // recursive coordinate bisection
      {"LB_APPROACH", "PARTITION"}, // from scratch every time (no incremental repartitioning)
      {"NUM_GID_ENTRIES", "1"},     // a global id below 2^32
      {"NUM_LID_ENTRIES", "1"},     // the item's place in PartitionItems
      {"OBJ_WEIGHT_DIM", "1"},      // one weight: the item's work
      {"RETURN_LISTS", "PARTS"},    // every item's part, moved or not
      {"IMBALANCE_TOL", "1.01"},    // each cut within 1 % of the weighted median, as far as the
                                    // items allow (Zoltan's default, 1.1, leaves up to 10 %)
      {"RCB_REUSE", "0"},           // no cuts kept from the last call: the parts depend on the
      {"KEEP_CUTS", "0"},           // items alone
  };
  for (const auto &[name, value] : settings)
    if (Zoltan_Set_Param(zoltan_, name, value) != ZOLTAN_OK)
      throw std::runtime_error(std::string("Zoltan refused the parameter ") + name + " = " + value);
}

ZoltanRcb::~ZoltanRcb() { Zoltan_Destroy(&zoltan_); }

std::vector<int> ZoltanRcb::partition(const PartitionItems &mine) const {
  int rank = 0;
  MPI_Comm_rank(comm_, &rank);
  const unsigned long total = allReduce<unsigned long>(mine.size(), MPI_SUM, comm_);
  if (total < 2)
    return std::vector<int>(mine.size(), rank);
  void *data = const_cast<PartitionItems *>(&mine); // Zoltan's callbacks take void *; read only
  Zoltan_Set_Num_Obj_Fn(zoltan_, itemCount, data);
  Zoltan_Set_Obj_List_Fn(zoltan_, itemList, data);
  Zoltan_Set_Num_Geom_Fn(zoltan_, dimensions, data);
  Zoltan_Set_Geom_Multi_Fn(zoltan_, points, data);
  int changes = 0, gid_entries = 0, lid_entries = 0, imports = 0, exports = 0;
  ZOLTAN_ID_PTR import_gids = nullptr, import_lids = nullptr, export_gids = nullptr,
                export_lids = nullptr;
  int *import_procs = nullptr, *import_parts = nullptr, *export_procs = nullptr,
      *export_parts = nullptr;
  const int status =
      Zoltan_LB_Partition(zoltan_, &changes, &gid_entries, &lid_entries, &imports, &import_gids,
                          &import_lids, &import_procs, &import_parts, &exports, &export_gids,
                          &export_lids, &export_procs, &export_parts);
  // An error (ZOLTAN_FATAL, ZOLTAN_MEMERR: negative; a warning is positive, its parts valid) on
  // any process, known to every one.
  const int worst = allReduce(std::min(status, 0), MPI_MIN, comm_);
  if (worst < 0) {
    Zoltan_LB_Free_Part(&import_gids, &import_lids, &import_procs, &import_parts);
    Zoltan_LB_Free_Part(&export_gids, &export_lids, &export_procs, &export_parts);
    throw std::runtime_error("Zoltan's RCB partition failed (status " + std::to_string(worst) +
                             ")");
  }
  // With RETURN_LISTS = PARTS the export lists hold every item of this process and its part;
  // parts are numbered as the processes (NUM_GLOBAL_PARTS is their number).
  std::vector<int> to(mine.size(), -1);
  for (int k = 0; k < exports; ++k)
    to[export_lids[k]] = export_parts[k];
  Zoltan_LB_Free_Part(&import_gids, &import_lids, &import_procs, &import_parts);
  Zoltan_LB_Free_Part(&export_gids, &export_lids, &export_procs, &export_parts);
  const int missing = static_cast<int>(std::count(to.begin(), to.end(), -1));
  if (allReduce(missing, MPI_MAX, comm_) > 0)
    throw std::runtime_error("Zoltan's RCB partition left an item without a part");
  return to;
}

} // namespace mesopen::parallel
