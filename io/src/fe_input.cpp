#include "mbsflow/io/fe_input.hpp"

#include <algorithm>
#include <array>
#include <cctype>
#include <cerrno>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <limits>
#include <fstream>
#include <set>
#include <sstream>
#include <string_view>

#include "mbsflow/error.hpp"
#include "mbsflow/io/file_text.hpp"

namespace mbsflow {
namespace {

std::string upper(std::string s) {
  for (char& c : s) c = static_cast<char>(std::toupper(static_cast<unsigned char>(c)));
  return s;
}

std::string trim(const std::string& s) {
  const auto a = s.find_first_not_of(" \t\r");
  if (a == std::string::npos) return "";
  return s.substr(a, s.find_last_not_of(" \t\r") - a + 1);
}

std::vector<std::string> split(const std::string& line, char sep) {
  std::vector<std::string> out;
  std::string item;
  std::istringstream in(line);
  while (std::getline(in, item, sep)) out.push_back(trim(item));
  if (!line.empty() && line.back() == sep) out.emplace_back();
  return out;
}

std::ifstream open(const std::string& path, const char* what) {
  std::ifstream in(path);
  if (!in) throw InputError(path + ": cannot read the " + std::string(what) + " (" + std::strerror(errno) + ")");
  return in;
}

// Node count of the element types drawn or reduced; 0: unknown (one data line each).
int nodes_of(const std::string& type) {
  static const std::map<std::string, int> count{
      {"C3D4", 4},   {"C3D10", 10}, {"C3D6", 6},  {"C3D15", 15}, {"C3D8", 8},   {"C3D8R", 8},  {"C3D8I", 8},
      {"C3D20", 20}, {"C3D20R", 20}, {"S3", 3},   {"S4", 4},     {"S4R", 4},    {"S6", 6},     {"S8", 8},
      {"S8R", 8},    {"B31", 2},    {"B32", 3},   {"B32R", 3},   {"T3D2", 2},   {"CPS4", 4},   {"CPE4", 4}};
  const auto at = count.find(type);
  return at == count.end() ? 0 : at->second;
}

struct DeckReader {
  FeMesh mesh;

  [[noreturn]] static void fail(const std::string& file, int line, const std::string& what) {
    throw InputError(file + ":" + std::to_string(line) + ": " + what);
  }

  static double number(const std::string& file, int line, const std::string& text) {
    char* end = nullptr;
    const double v = std::strtod(text.c_str(), &end);
    if (text.empty() || *end != '\0') fail(file, line, "'" + text + "' is not a number");
    return v;
  }

  static long integer(const std::string& file, int line, const std::string& text) {
    char* end = nullptr;
    const long v = std::strtol(text.c_str(), &end, 10);
    if (text.empty() || *end != '\0') fail(file, line, "'" + text + "' is not a whole number");
    return v;
  }

  // A keyword line's parameters, names upper case ("TYPE" -> "C3D8").
  static std::map<std::string, std::string> parameters(const std::vector<std::string>& parts) {
    std::map<std::string, std::string> p;
    for (std::size_t k = 1; k < parts.size(); ++k) {
      const auto eq = parts[k].find('=');
      p[upper(trim(parts[k].substr(0, eq)))] = eq == std::string::npos ? "" : trim(parts[k].substr(eq + 1));
    }
    return p;
  }

  void read(const std::string& path, int depth) {
    if (depth > 8) throw InputError(path + ": *INCLUDE nested more than 8 deep");
    std::ifstream in = open(path, "finite-element deck");
    std::string text, keyword, set_name, element_type;
    std::map<std::string, std::string> params;
    std::vector<long> pending;  // an element whose nodes continue on the next line
    int line = 0;
    while (std::getline(in, text)) {
      ++line;
      const std::string t = trim(text);
      if (t.empty() || t.rfind("**", 0) == 0) continue;
      if (t[0] == '*') {
        if (!pending.empty()) fail(path, line, "element " + std::to_string(pending[0]) + " has too few nodes");
        const std::vector<std::string> parts = split(t, ',');
        keyword = upper(parts[0]);
        params = parameters(parts);
        if (keyword == "*INCLUDE") {
          const std::filesystem::path input = params["INPUT"];
          read((input.is_absolute() ? input : std::filesystem::path(path).parent_path() / input).string(), depth + 1);
          keyword.clear();
        } else if (keyword == "*NODE" || keyword == "*ELEMENT") {
          set_name = upper(params[keyword == "*NODE" ? "NSET" : "ELSET"]);
          element_type = upper(params["TYPE"]);
          if (keyword == "*ELEMENT" && element_type.empty()) fail(path, line, "*ELEMENT without TYPE=");
        } else if (keyword == "*NSET") {
          set_name = upper(params["NSET"]);
          if (set_name.empty()) fail(path, line, "*NSET without NSET=");
          mesh.node_sets[set_name];
        }
        continue;
      }
      std::vector<std::string> items = split(t, ',');
      if (!items.empty() && items.back().empty()) items.pop_back();
      if (keyword == "*NODE") {
        if (items.size() < 2 || items.size() > 4) fail(path, line, "a node is 'number, x[, y[, z]]'");
        const long id = integer(path, line, items[0]);
        Eigen::Vector3d x = Eigen::Vector3d::Zero();
        for (std::size_t k = 1; k < items.size(); ++k) x[static_cast<Eigen::Index>(k - 1)] = number(path, line, items[k]);
        if (!mesh.node_index.emplace(id, mesh.node_id.size()).second) fail(path, line, "node " + std::to_string(id) + " is defined twice");
        mesh.node_id.push_back(id);
        mesh.node_position.push_back(x);
        if (!set_name.empty()) mesh.node_sets[set_name].push_back(id);
      } else if (keyword == "*ELEMENT") {
        for (const std::string& item : items) pending.push_back(integer(path, line, item));
        const int want = nodes_of(element_type);
        if (want > 0 && static_cast<int>(pending.size()) < want + 1) continue;  // continues on the next line
        if (want > 0 && static_cast<int>(pending.size()) > want + 1)
          fail(path, line, element_type + " element " + std::to_string(pending[0]) + " has more than " + std::to_string(want) + " nodes");
        mesh.elements.push_back({element_type, std::vector<long>(pending.begin() + 1, pending.end())});
        pending.clear();
      } else if (keyword == "*NSET") {
        std::vector<long>& set = mesh.node_sets[set_name];
        if (params.count("GENERATE")) {
          if (items.size() < 2 || items.size() > 3) fail(path, line, "*NSET, GENERATE takes 'first, last[, step]'");
          const long a = integer(path, line, items[0]), b = integer(path, line, items[1]);
          const long step = items.size() == 3 ? integer(path, line, items[2]) : 1;
          if (step <= 0 || b < a) fail(path, line, "*NSET, GENERATE: first <= last and step > 0");
          for (long k = a; k <= b; k += step) set.push_back(k);
        } else {
          for (const std::string& item : items) {
            if (!item.empty() && (std::isdigit(static_cast<unsigned char>(item[0])) || item[0] == '-')) {
              set.push_back(integer(path, line, item));
            } else {
              const auto other = mesh.node_sets.find(upper(item));
              if (other == mesh.node_sets.end()) fail(path, line, "no node set " + item + " before this line");
              set.insert(set.end(), other->second.begin(), other->second.end());
            }
          }
        }
      }
    }
    if (!pending.empty()) fail(path, line, "element " + std::to_string(pending[0]) + " has too few nodes");
  }
};

// "r c v" lines of one matrix of n rows; one triangle filled in with the other, unless
// the file holds entries on both sides of the diagonal (then taken as they are).
Eigen::SparseMatrix<double> read_triplets(const std::string& path, Eigen::Index n, bool matrix_market) {
  // Mapped, not read through streams: a large part's matrices are hundreds of megabytes.
  const FileText file(path, "matrix", std::numeric_limits<std::size_t>::max());
  const std::string_view text = file.text();
  std::vector<Eigen::Triplet<double>> t;
  bool upper_seen = false, lower_seen = false, symmetric = !matrix_market, header = matrix_market;
  const char* p = text.data();
  const char* const end = p + text.size();
  char buffer[256];  // the line being parsed, NUL-terminated: strtol and strtod stop there
  int line = 0;
  while (p < end) {
    ++line;
    const char* eol = static_cast<const char*>(std::memchr(p, '\n', static_cast<std::size_t>(end - p)));
    if (!eol) eol = end;
    const std::string_view row(p, static_cast<std::size_t>(eol - p));
    p = eol + 1;
    if (matrix_market && !row.empty() && row[0] == '%') {
      if (line == 1) {
        const std::string h = upper(std::string(row));
        if (h.find("COORDINATE") == std::string::npos || h.find("COMPLEX") != std::string::npos || h.find("PATTERN") != std::string::npos)
          throw InputError(path + ":1: a Matrix Market file of real coordinates is needed (" + trim(std::string(row)) + ")");
        symmetric = h.find("SYMMETRIC") != std::string::npos;
      }
      continue;
    }
    if (row.find_first_not_of(" \t\r") == std::string_view::npos) continue;
    const auto fail = [&](const std::string& what) { throw InputError(path + ":" + std::to_string(line) + ": " + what); };
    if (row.size() >= sizeof buffer) fail("a line of over " + std::to_string(sizeof buffer - 1) + " characters");
    std::memcpy(buffer, row.data(), row.size());
    buffer[row.size()] = '\0';
    char* next = nullptr;
    const long r = std::strtol(buffer, &next, 10);
    const long c = std::strtol(next, &next, 10);
    if (header) {  // rows, columns, entries
      if (r != n || c != n)
        fail("the matrix must be " + std::to_string(n) + " x " + std::to_string(n) + " (a row per DOF of the map)");
      header = false;
      continue;
    }
    const char* number = next;
    const double v = std::strtod(number, &next);
    if (next == number || r < 1 || c < 1 || r > n || c > n)
      fail("expected 'row column value' with rows and columns 1.." + std::to_string(n));
    upper_seen |= c > r;
    lower_seen |= r > c;
    t.emplace_back(r - 1, c - 1, v);
  }
  // Both triangles stored: nothing to fill in (a general file, or a symmetric one written whole).
  if (symmetric && !(upper_seen && lower_seen)) {
    const std::size_t stored = t.size();
    t.reserve(2 * stored);
    for (std::size_t k = 0; k < stored; ++k)
      if (t[k].row() != t[k].col()) t.emplace_back(t[k].col(), t[k].row(), t[k].value());
  }
  Eigen::SparseMatrix<double> m(n, n);
  m.setFromTriplets(t.begin(), t.end());
  return m;
}

std::vector<FeDof> read_dofs(const std::string& path) {
  std::ifstream in = open(path, "DOF map");
  std::vector<FeDof> dofs;
  std::string text;
  int line = 0;
  while (std::getline(in, text)) {
    ++line;
    const std::string t = trim(text);
    if (t.empty()) continue;
    const auto dot = t.find('.');
    char* end = nullptr;
    FeDof d;
    d.node = std::strtol(t.c_str(), &end, 10);
    const bool ok = dot != std::string::npos && end == t.c_str() + dot && dot + 2 == t.size() && t[dot + 1] >= '1' && t[dot + 1] <= '6';
    if (!ok) throw InputError(path + ":" + std::to_string(line) + ": expected 'node.direction' (direction 1..6), got '" + t + "'");
    d.direction = t[dot + 1] - '0';
    dofs.push_back(d);
  }
  if (dofs.empty()) throw InputError(path + ": no DOFs");
  return dofs;
}

}  // namespace

FeMesh read_fe_deck(const std::string& path) {
  DeckReader r;
  r.read(path, 0);
  if (r.mesh.node_id.empty()) throw InputError(path + ": no *NODE in the deck");
  for (const FeElement& e : r.mesh.elements)
    for (long node : e.nodes)
      if (!r.mesh.node_index.count(node))
        throw InputError(path + ": an " + e.type + " element names node " + std::to_string(node) + ", which no *NODE defines");
  return std::move(r.mesh);
}

FeMatrices read_calculix_matrices(const std::string& job) {
  for (const char* ext : {".sti", ".mas", ".dof"})
    if (!std::filesystem::exists(job + ext))
      throw InputError(job + ext + ": not there; CalculiX writes JOB.sti, JOB.mas and JOB.dof for a step "
                       "'*FREQUENCY, SOLVER=MATRIXSTORAGE' (ccx JOB; docs/flexible.md)");
  FeMatrices m;
  m.dofs = read_dofs(job + ".dof");
  const auto n = static_cast<Eigen::Index>(m.dofs.size());
  m.stiffness = read_triplets(job + ".sti", n, false);
  m.mass = read_triplets(job + ".mas", n, false);
  return m;
}

FeMatrices read_matrix_market(const std::string& stiffness, const std::string& mass, const std::string& dof_map) {
  FeMatrices m;
  m.dofs = read_dofs(dof_map);
  const auto n = static_cast<Eigen::Index>(m.dofs.size());
  m.stiffness = read_triplets(stiffness, n, true);
  m.mass = read_triplets(mass, n, true);
  return m;
}

std::vector<std::array<long, 3>> outer_triangles(const FeMesh& mesh) {
  using Face = std::vector<int>;  // corner positions in the element
  static const std::map<int, std::vector<Face>> solid_faces{
      {4, {{0, 2, 1}, {0, 1, 3}, {1, 2, 3}, {0, 3, 2}}},
      {6, {{0, 2, 1}, {3, 4, 5}, {0, 1, 4, 3}, {1, 2, 5, 4}, {2, 0, 3, 5}}},
      {8, {{0, 3, 2, 1}, {4, 5, 6, 7}, {0, 1, 5, 4}, {1, 2, 6, 5}, {2, 3, 7, 6}, {3, 0, 4, 7}}}};
  std::map<std::vector<long>, std::pair<int, std::vector<long>>> faces;  // sorted corners -> count, corners in order
  std::vector<std::vector<long>> shells;
  for (const FeElement& e : mesh.elements) {
    const std::string& t = e.type;
    int corners = 0;
    if (t.rfind("C3D4", 0) == 0 || t.rfind("C3D10", 0) == 0) corners = 4;
    else if (t.rfind("C3D6", 0) == 0 || t.rfind("C3D15", 0) == 0) corners = 6;
    else if (t.rfind("C3D8", 0) == 0 || t.rfind("C3D20", 0) == 0) corners = 8;
    if (corners > 0 && static_cast<int>(e.nodes.size()) >= corners) {
      for (const Face& f : solid_faces.at(corners)) {
        std::vector<long> ordered;
        for (int k : f) ordered.push_back(e.nodes[static_cast<std::size_t>(k)]);
        std::vector<long> key = ordered;
        std::sort(key.begin(), key.end());
        auto& [count, order] = faces[key];
        if (count++ == 0) order = ordered;
      }
    } else if ((t[0] == 'S' || t.rfind("CP", 0) == 0) && e.nodes.size() >= 3) {
      shells.emplace_back(e.nodes.begin(), e.nodes.begin() + (e.nodes.size() >= 8 || e.nodes.size() == 4 ? 4 : 3));
    }
  }
  std::vector<std::array<long, 3>> out;
  const auto add = [&](const std::vector<long>& f) {
    out.push_back({f[0], f[1], f[2]});
    if (f.size() == 4) out.push_back({f[0], f[2], f[3]});
  };
  for (const auto& [key, face] : faces)
    if (face.first == 1) add(face.second);
  for (const auto& s : shells) add(s);
  return out;
}

std::vector<long> parse_node_list(const std::string& text, const FeMesh& mesh) {
  std::vector<long> out;
  std::string item;
  std::string spaced = text;
  std::replace(spaced.begin(), spaced.end(), ',', ' ');
  std::istringstream in(spaced);
  while (in >> item) {
    if (std::isdigit(static_cast<unsigned char>(item[0]))) {
      const auto dash = item.find('-');
      char* end = nullptr;
      const long a = std::strtol(item.c_str(), &end, 10);
      long b = a;
      if (dash != std::string::npos) b = std::strtol(item.c_str() + dash + 1, &end, 10);
      if (*end != '\0' || b < a) throw InputError("--interface: '" + item + "' is neither a node number, a range a-b nor a node set");
      for (long k = a; k <= b; ++k) {
        if (!mesh.node_index.count(k)) throw InputError("--interface: node " + std::to_string(k) + " is not in the deck");
        out.push_back(k);
      }
    } else {
      const auto set = mesh.node_sets.find(upper(item));
      if (set == mesh.node_sets.end()) throw InputError("--interface: the deck has no node set " + item);
      out.insert(out.end(), set->second.begin(), set->second.end());
    }
  }
  // A node named twice (in two sets, say) is kept once, in its first place.
  std::vector<long> unique;
  std::set<long> seen;
  for (long k : out)
    if (seen.insert(k).second) unique.push_back(k);
  return unique;
}

}  // namespace mbsflow
