#pragma once
// The partitioned CPU engine (docs/multi-gpu.md): one MPI rank per part of make_partition, each
// running the shared loop bodies (simulator/passes/) on its part, with the same bits as the
// one-device CPU engine (make_cpu_backend) for any number of ranks.
//
// Each rank keeps the model's arrays whole (EngineArrays, BackendCore) and u(n), u(n−1) valid on
// its owned and halo nodes. One step on a rank:
//  1. elements touching a node other parts need (boundary elements), then the owned nodes those
//     parts need: gather (one-device incidence order), central-difference update, loads and
//     constraints; their u(n+1) sent (MPI_Isend) while
//  2. the interior elements and the rest of the owned nodes are computed;
//  3. the halo nodes' u(n+1) received (MPI_Waitall).
// Checks and sums that one device makes over all items are made here in the one-device order, so
// they are the same bits: the smallest J (every step: each rank's primary elements, the ranks'
// results merged in collection order) and the first non-finite node (every step, gathered with
// the J results); the external work (every constrained node's work terms, add_program_work, on
// every rank from its owner's u(n+1), u(n−1), projections' moves and u*, in the one-device chunk
// order; the weights' work from every node's terms, gathered); at energy steps
// the kinetic, strain and hourglass energies (u and u(n−1) gathered whole; the one-device chunks
// of 1024 elements dealt to the ranks, their sums gathered and added in order).
//
// Every Backend method is collective: all ranks call the same methods in the same order, and each
// gets the whole result (displacements, energies, state, fields). A checkpoint holds the whole
// state, so it restarts on any number of ranks.
// Sliding nodes belong to the part owning them (their lists and warm starts live there; a sliding
// node may carry loads and prescribed displacements too); the surfaces are on every rank.
#include <memory>

#include <mpi.h>

#include "sinew/formats/model.hpp"
#include "sinew/simulator/engine/backend.hpp"
#include "sinew/simulator/engine/cpu_engine.hpp"
#include "sinew/simulator/engine/setup.hpp"

namespace sinew::partition {

// The partitioned CPU backend on `comm` (one part per rank, make_partition with work_of). Collective.
// Throws ConfigError for a bad Setup (as make_cpu_backend).
std::unique_ptr<simulator::Backend> make_partitioned_cpu_backend(const formats::Model& model,
                                                                 const simulator::Setup& setup,
                                                                 MPI_Comm comm);

}  // namespace sinew::partition
