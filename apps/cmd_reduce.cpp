// mbsflow reduce DECK.inp --interface NODES --modes K -o part.h5: a finite-element part
// reduced by Craig-Bampton (docs/flexible.md), from the matrices CalculiX writes or from
// Matrix Market files.
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <memory>

#include "commands.hpp"
#include "mbsflow/error.hpp"
#include "mbsflow/io/fe_input.hpp"
#include "mbsflow/io/output_path.hpp"
#include "mbsflow/io/reduced_part_file.hpp"

namespace mbsflow::cli {
namespace {

struct ReduceArgs {
  std::string deck, matrices, stiffness, mass, dof_map, output = "part.h5";
  std::vector<std::string> interface, rigid_faces;
  int modes = 10;
  bool force = false, quiet = false;
};

double seconds_since(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

int reduce(const ReduceArgs& a) {
  const auto start = std::chrono::steady_clock::now();
  const bool market = !a.stiffness.empty() || !a.mass.empty() || !a.dof_map.empty();
  if (market && (a.stiffness.empty() || a.mass.empty() || a.dof_map.empty()))
    throw InputError("--stiffness, --mass and --dofs go together (Matrix Market files and their DOF map)");
  if (market && !a.matrices.empty()) throw InputError("--matrices (CalculiX's) or --stiffness/--mass/--dofs, not both");
  if (a.interface.empty() && a.rigid_faces.empty()) throw InputError("give the interface: --interface NODES or --rigid-face SET");
  check_output_path(a.output, {{a.deck, a.stiffness, a.mass, a.dof_map}, a.force});
  const auto phase = [&](const char* what) {
    if (!a.quiet) std::fprintf(stderr, "mbsflow: %.1f s: %s\n", seconds_since(start), what);
  };
  phase("read the deck");
  FeMesh mesh = read_fe_deck(a.deck);
  std::string job = a.matrices;
  if (job.empty() && !market) {
    const std::filesystem::path deck(a.deck);
    job = (deck.parent_path() / deck.stem()).string();  // ccx JOB writes JOB.sti beside JOB.inp
  }
  phase("read the matrices");
  FeMatrices fe = market ? read_matrix_market(a.stiffness, a.mass, a.dof_map) : read_calculix_matrices(job);
  std::vector<Eigen::Vector3d> dof_position;
  for (const FeDof& d : fe.dofs) {
    const auto at = mesh.node_index.find(d.node);
    if (at == mesh.node_index.end())
      throw InputError("the matrices have a DOF on node " + std::to_string(d.node) + ", which " + a.deck + " does not define");
    dof_position.push_back(mesh.node_position[at->second]);
  }
  std::string list;
  for (const std::string& s : a.interface) list += s + " ";
  CraigBamptonOptions o;
  o.interface_nodes = parse_node_list(list, mesh);
  if (o.interface_nodes.empty() && a.rigid_faces.empty()) throw InputError("give the interface: --interface NODES or --rigid-face SET");
  // Each rigid face: its nodes tied to a new 6-DOF master node at their centroid, numbered
  // after the deck's last node; the masters join the interface.
  const std::vector<FeDof> model_dofs = fe.dofs;
  Eigen::SparseMatrix<double> tie;
  long next_node = *std::max_element(mesh.node_id.begin(), mesh.node_id.end()) + 1;
  for (const std::string& face : a.rigid_faces) {
    const std::vector<long> nodes = parse_node_list(face, mesh);
    Eigen::Vector3d centre = Eigen::Vector3d::Zero();
    for (long node : nodes) centre += mesh.node_position[mesh.node_index.at(node)];
    centre /= static_cast<double>(nodes.size());
    const long master = next_node++;
    TiedModel tied = tie_rigidly(fe, dof_position, nodes, master, centre);
    fe = std::move(tied.fe);
    dof_position = std::move(tied.dof_position);
    tie = tie.size() == 0 ? tied.tie : Eigen::SparseMatrix<double>(tie * tied.tie);
    mesh.node_index.emplace(master, mesh.node_id.size());
    mesh.node_id.push_back(master);
    mesh.node_position.push_back(centre);
    o.interface_nodes.push_back(master);
    if (!a.quiet)
      std::fprintf(stderr, "mbsflow: %s: %zu nodes tied rigidly to node %ld at (%.6g, %.6g, %.6g), its 6 DOFs in the interface\n",
                   face.c_str(), nodes.size(), master, centre.x(), centre.y(), centre.z());
  }
  o.modes = a.modes;
  o.phase = phase;
  if (!a.quiet)
    std::fprintf(stderr, "mbsflow: %s: %zu nodes, %zu elements; %zu DOFs (%s); interface %zu node%s\n", a.deck.c_str(),
                 mesh.node_id.size(), mesh.elements.size(), fe.dofs.size(),
                 market ? "Matrix Market" : (job + ".sti/.mas/.dof").c_str(), o.interface_nodes.size(),
                 o.interface_nodes.size() == 1 ? "" : "s");
  ReducedPart part = craig_bampton(fe, dof_position, o);
  if (tie.size() > 0) part.shapes = tie * part.shapes;  // the tied faces' nodes move with their masters
  const double reduced_in = seconds_since(start);
  phase("write the reduced part");
  write_reduced_part(a.output, part, model_dofs, mesh, {a.deck, invocation()});
  if (!a.quiet) {
    const MassProperties& p = part.properties;
    std::fprintf(stderr, "mbsflow: mass %.6g kg, centre (%.6g, %.6g, %.6g) m, inertia about it diag (%.6g, %.6g, %.6g) kg m^2\n",
                 p.mass, p.centre.x(), p.centre.y(), p.centre.z(), p.inertia(0, 0), p.inertia(1, 1), p.inertia(2, 2));
    if (part.modes > 0)
      std::fprintf(stderr, "mbsflow: %d fixed-interface mode%s, %.6g .. %.6g Hz\n", part.modes, part.modes == 1 ? "" : "s",
                   part.fixed_frequency[0], part.fixed_frequency[part.modes - 1]);
    // Free, a part has its six rigid-body motions first (frequencies at rounding's level).
    std::fprintf(stderr, "mbsflow: the reduced part free: %s\n", free_frequencies_text(part).c_str());
  }
  std::fprintf(stderr, "mbsflow: wrote %s: %td coordinates (%zu interface DOFs + %d modes), reduced in %.3g s\n", a.output.c_str(),
               part.mass.rows(), part.interface_dofs.size(), part.modes, reduced_in);
  return 0;
}

}  // namespace

Action add_reduce(CLI::App& app) {
  auto a = std::make_shared<ReduceArgs>();
  CLI::App* sub = app.add_subcommand(
      "reduce", "Reduce a finite-element part by Craig-Bampton (its interface nodes kept, fixed-interface modes added) "
                "into one HDF5 file: its matrices, mass, inertia, surface and floating-frame data, which a model uses as a "
                "flexible body, {\"type\": \"flexible\", \"file\": ...} (docs/flexible.md)");
  sub->add_option("deck", a->deck, "The part's CalculiX/Abaqus input deck (.inp): its nodes, elements and node sets")
      ->required()
      ->check(CLI::ExistingFile);
  sub->add_option("--interface", a->interface,
                  "Interface nodes: numbers, ranges a-b, or node set names of the deck (several allowed)");
  sub->add_option("--rigid-face", a->rigid_faces,
                  "A node set (or list) tied rigidly to a new 6-DOF master node at its centroid, which joins the interface "
                  "(an RBE2 spider; repeat for several faces)");
  sub->add_option("--modes", a->modes, "Fixed-interface modes to keep")->capture_default_str()->check(CLI::Range(0, 100000));
  sub->add_option("--matrices", a->matrices,
                  "CalculiX job whose JOB.sti, JOB.mas, JOB.dof hold the matrices (default: the deck's path without .inp)");
  sub->add_option("--stiffness", a->stiffness, "Instead: the stiffness matrix as a Matrix Market file")->check(CLI::ExistingFile);
  sub->add_option("--mass", a->mass, "... the mass matrix as a Matrix Market file")->check(CLI::ExistingFile);
  sub->add_option("--dofs", a->dof_map, "... and the DOF of each row, 'node.direction' per line (CalculiX's .dof form)")
      ->check(CLI::ExistingFile);
  sub->add_option("-o,--output", a->output, "The reduced part's file")->capture_default_str();
  sub->add_flag("--force", a->force, "With -o: replace the file there even if it is not an mbsflow file");
  sub->add_flag("-q,--quiet", a->quiet, "Print only the closing line");
  return [a] { return reduce(*a); };
}

}  // namespace mbsflow::cli
