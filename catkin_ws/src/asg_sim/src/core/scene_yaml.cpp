#include "asg_sim/scene_yaml.hpp"

#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <fstream>
#include <iterator>
#include <regex>
#include <set>
#include <sstream>

namespace asg_sim {
namespace {

// A plain YAML scalar resolved the way PyYAML (YAML 1.1) resolves it, so that this loader and
// asg_scenario's Python validator see the same types in the same file: "1e5" is a string and
// "1.0e+5" a float, "yes"/"off" are booleans, a quoted scalar is always a string.
struct Scalar {
  enum Kind { kNull, kBool, kInt, kFloat, kStr, kNotScalar } kind = kNull;
  bool b = false;
  long double num = 0;  // kInt and kFloat
  std::string text;
};

const char* kindName(Scalar::Kind k) {
  switch (k) {
    case Scalar::kNull: return "null";
    case Scalar::kBool: return "bool";
    case Scalar::kInt: return "int";
    case Scalar::kFloat: return "float";
    case Scalar::kStr: return "str";
    case Scalar::kNotScalar: return "a mapping or list";
  }
  return "?";
}

std::string stripUnderscores(std::string s) {
  s.erase(std::remove(s.begin(), s.end(), '_'), s.end());
  return s;
}

Scalar resolve(const YAML::Node& n) {
  Scalar v;
  if (n.IsNull()) return v;
  if (!n.IsScalar()) {
    v.kind = Scalar::kNotScalar;
    return v;
  }
  v.text = n.Scalar();
  if (n.Tag() == "!") {  // quoted
    v.kind = Scalar::kStr;
    return v;
  }
  const std::string& t = v.text;
  static const std::regex null_re("~|null|Null|NULL|");
  static const std::regex true_re("yes|Yes|YES|true|True|TRUE|on|On|ON");
  static const std::regex false_re("no|No|NO|false|False|FALSE|off|Off|OFF");
  static const std::regex dec_re("[-+]?(0|[1-9][0-9_]*)");
  static const std::regex hex_re("[-+]?0x[0-9a-fA-F_]+");
  static const std::regex oct_re("[-+]?0[0-7_]+");
  static const std::regex bin_re("[-+]?0b[0-1_]+");
  static const std::regex float_re("[-+]?([0-9][0-9_]*)?\\.[0-9_]*([eE][-+][0-9]+)?");
  static const std::regex inf_re("[-+]?\\.(inf|Inf|INF)");
  static const std::regex nan_re("\\.(nan|NaN|NAN)");
  if (std::regex_match(t, null_re)) return v;
  if (std::regex_match(t, true_re) || std::regex_match(t, false_re)) {
    v.kind = Scalar::kBool;
    v.b = std::regex_match(t, true_re);
    return v;
  }
  auto integer = [&](int base, size_t prefix) {
    std::string digits = stripUnderscores(t);
    bool neg = false;
    if (!digits.empty() && (digits[0] == '-' || digits[0] == '+')) {
      neg = digits[0] == '-';
      digits = digits.substr(1);
    }
    digits = digits.substr(prefix);
    long double x = 0;
    for (char c : digits) x = x * base + (std::isdigit(c) ? c - '0' : std::tolower(c) - 'a' + 10);
    v.kind = Scalar::kInt;
    v.num = neg ? -x : x;
  };
  if (std::regex_match(t, dec_re)) integer(10, 0);
  else if (std::regex_match(t, hex_re)) integer(16, 2);
  else if (std::regex_match(t, bin_re)) integer(2, 2);
  else if (std::regex_match(t, oct_re)) integer(8, 1);
  else if (std::regex_match(t, inf_re)) {
    v.kind = Scalar::kFloat;
    v.num = t[0] == '-' ? -INFINITY : INFINITY;
  } else if (std::regex_match(t, nan_re)) {
    v.kind = Scalar::kFloat;
    v.num = NAN;
  } else if (t != "." && std::regex_match(t, float_re)) {
    v.kind = Scalar::kFloat;
    v.num = std::strtold(stripUnderscores(t).c_str(), nullptr);
  } else {
    v.kind = Scalar::kStr;
  }
  return v;
}

// Collects every problem, as the Python validator does, then throws them together.
class Reader {
 public:
  explicit Reader(std::string source) : source_(std::move(source)) {}

  void fail(const std::string& path, const std::string& msg) {
    out_ << "\n  - " << path << ": " << msg;
    ++n_;
  }
  void raise() const {
    if (n_) throw SceneError(source_ + ": invalid scene, " + std::to_string(n_) + " problem(s):" + out_.str());
  }

  /// The node if it is a mapping (nullptr-like empty node otherwise, with a problem).
  YAML::Node mapping(const YAML::Node& n, const std::string& path, bool required = true) {
    if (!n || n.IsNull()) {
      if (required) fail(path, "missing section (a mapping is required)");
      return YAML::Node(YAML::NodeType::Map);
    }
    if (!n.IsMap()) {
      fail(path, "must be a mapping");
      return YAML::Node(YAML::NodeType::Map);
    }
    return n;
  }

  /// A problem for each key of `map` that is not in `keys` (a key list of scene_schema.hpp).
  template <std::size_t N>
  void allowOnly(const YAML::Node& map, const char* const (&keys)[N], const std::string& path) {
    const std::set<std::string> known(std::begin(keys), std::end(keys));
    std::string allowed;
    for (const auto& k : known) allowed += (allowed.empty() ? "" : ", ") + k;
    for (const auto& kv : map) {
      const std::string key = kv.first.IsScalar() ? kv.first.Scalar() : "?";
      if (!known.count(key)) fail(join(path, key), "unknown field (allowed: " + allowed + ")");
    }
  }

  // The readers of one field of the schema: its key is the last part of the field's dotted key,
  // it is required when the schema gives no default, and an integer's bounds are the field's.
  void number(const YAML::Node& map, const schema::Field& f, double* out, const std::string& path) {
    Scalar v;
    if (!present(map, f, path, &v)) return;
    if (v.kind != Scalar::kInt && v.kind != Scalar::kFloat) {
      fail(join(path, key(f)), "= " + show(v) + ": wrong type " + kindName(v.kind) + ", must be a finite number");
      return;
    }
    // Finite values beyond double become +-inf, which validateScene names as not finite.
    *out = double(v.num);
    if (v.kind == Scalar::kInt && !std::isfinite(*out)) fail(join(path, key(f)), "= " + v.text + ": out of range");
  }

  template <class T>
  void integer(const YAML::Node& map, const schema::Field& f, T* out, const std::string& path) {
    Scalar v;
    if (!present(map, f, path, &v)) return;
    const bool integral = v.kind == Scalar::kInt ||
                          (v.kind == Scalar::kFloat && std::isfinite(v.num) && v.num == std::floor(v.num));
    if (!integral) {
      fail(join(path, key(f)), "= " + show(v) + ": wrong type " + kindName(v.kind) + ", must be an integer");
      return;
    }
    if (v.num < f.lo || v.num > f.hi) {
      std::ostringstream s;
      s << "= " << v.text << ": out of range, must be an integer in [" << f.lo << ", " << f.hi << "]";
      fail(join(path, key(f)), s.str());
      return;
    }
    *out = T(v.num);
  }

  void boolean(const YAML::Node& map, const schema::Field& f, bool* out, const std::string& path) {
    Scalar v;
    if (!present(map, f, path, &v)) return;
    if (v.kind != Scalar::kBool) {
      fail(join(path, key(f)), "= " + show(v) + ": wrong type " + kindName(v.kind) + ", must be true or false");
      return;
    }
    *out = v.b;
  }

  void string(const YAML::Node& map, const char* key, std::string* out, const std::string& path, bool required) {
    Scalar v;
    if (!present(map, key, path, required, &v)) return;
    if (v.kind != Scalar::kStr) {
      fail(join(path, key), "= " + show(v) + ": wrong type " + kindName(v.kind) + ", must be a string");
      return;
    }
    *out = v.text;
  }

  static std::string join(const std::string& path, const std::string& key) {
    return path.empty() ? key : path + "." + key;
  }

 private:
  static std::string key(const schema::Field& f) {
    const char* dot = std::strrchr(f.key, '.');
    return dot ? dot + 1 : f.key;
  }
  bool present(const YAML::Node& map, const schema::Field& f, const std::string& path, Scalar* v) {
    return present(map, key(f).c_str(), path, std::isnan(f.default_value), v);
  }
  bool present(const YAML::Node& map, const char* key, const std::string& path, bool required, Scalar* v) {
    const YAML::Node n = map[key];
    if (!n) {
      if (required) fail(join(path, key), "missing required field");
      return false;
    }
    *v = resolve(n);
    return true;
  }
  static std::string show(const Scalar& v) { return v.kind == Scalar::kNotScalar ? "(not a scalar)" : "'" + v.text + "'"; }

  std::string source_;
  std::ostringstream out_;
  int n_ = 0;
};

// Offset of the first byte that is not part of well-formed UTF-8, or of a character YAML does not
// allow in a stream (C0/C1 controls other than tab, newline and carriage return, surrogates,
// U+FFFE/U+FFFF); npos when there is none. The Python loader reads scenario files as UTF-8 and
// PyYAML refuses those characters: this loader refuses the same files. *why says which.
size_t firstBadCharacter(const std::string& s, std::string* why) {
  size_t i = 0;
  while (i < s.size()) {
    const unsigned char c = s[i];
    const int n = c < 0x80 ? 0 : (c >> 5) == 0x6 ? 1 : (c >> 4) == 0xe ? 2 : (c >> 3) == 0x1e ? 3 : -1;
    *why = "not UTF-8 text";
    if (n < 0 || c == 0xc0 || c == 0xc1 || c > 0xf4 || (n > 0 && i + n >= s.size())) return i;
    uint32_t cp = n == 0 ? c : n == 1 ? (c & 0x1f) : n == 2 ? (c & 0x0f) : (c & 0x07);
    for (int k = 1; k <= n; ++k) {
      const unsigned char d = s[i + k];
      if ((d >> 6) != 0x2) return i;
      cp = (cp << 6) | (d & 0x3f);
    }
    if ((n == 2 && cp < 0x800) || (n == 3 && (cp < 0x10000 || cp > 0x10ffff)) || (cp >= 0xd800 && cp <= 0xdfff))
      return i;  // overlong, out of range or a surrogate
    const bool printable = cp == 0x9 || cp == 0xa || cp == 0xd || (cp >= 0x20 && cp <= 0x7e) || cp == 0x85 ||
                           (cp >= 0xa0 && cp <= 0xd7ff) || (cp >= 0xe000 && cp <= 0xfffd) || cp >= 0x10000;
    if (!printable) {
      *why = "a control character YAML does not allow";
      return i;
    }
    i += n + 1;
  }
  return std::string::npos;
}

// A key given twice in one mapping (yaml-cpp keeps the first, PyYAML the last: refused by both
// loaders instead). Returns "" or the key and where.
std::string duplicateKey(const YAML::Node& n, int depth = 0) {
  if (depth > 64) return "";
  if (n.IsMap()) {
    std::set<std::string> seen;
    for (const auto& kv : n) {
      const std::string key = kv.first.IsScalar() ? kv.first.Scalar() : "";
      if (kv.first.IsScalar() && !seen.insert(key).second)
        return "key '" + key + "' is given twice in one mapping (line " + std::to_string(kv.first.Mark().line + 1) + ")";
      const std::string inner = duplicateKey(kv.second, depth + 1);
      if (!inner.empty()) return inner;
    }
  } else if (n.IsSequence()) {
    for (const auto& v : n) {
      const std::string inner = duplicateKey(v, depth + 1);
      if (!inner.empty()) return inner;
    }
  }
  return "";
}

namespace sc = schema;

void readTerrain(Reader& r, const YAML::Node& node, TerrainSpec* t) {
  const std::string tp = "structural.terrain";
  const YAML::Node tr = r.mapping(node, tp);
  r.allowOnly(tr, sc::kKeysTerrain, tp);
  r.number(tr, sc::kTerrainAmplitudeM, &t->amplitude_m, tp);
  r.number(tr, sc::kTerrainWavelengthM, &t->wavelength_m, tp);
  r.integer(tr, sc::kTerrainSeed, &t->seed, tp);
  const YAML::Node hills = tr["hills"];
  if (hills && !hills.IsSequence()) {
    r.fail(tp + ".hills", "must be a list of hills");
    return;
  }
  for (size_t i = 0; hills && i < hills.size(); ++i) {
    const std::string hp = tp + ".hills[" + std::to_string(i) + "]";
    const YAML::Node h = r.mapping(hills[i], hp);
    r.allowOnly(h, sc::kKeysHill, hp);
    Hill hill;
    r.number(h, sc::kHillX, &hill.x, hp);
    r.number(h, sc::kHillY, &hill.y, hp);
    r.number(h, sc::kHillRadiusM, &hill.radius_m, hp);
    r.number(h, sc::kHillHeightM, &hill.height_m, hp);
    t->hills.push_back(hill);
  }
}

void readLayouts(Reader& r, const YAML::Node& layouts, std::vector<ObstacleLayout>* out) {
  if (!layouts) return;  // absent: none; null is refused, as in Python
  if (!layouts.IsSequence()) {
    r.fail("structural.layouts", "must be a list of layouts");
    return;
  }
  for (size_t i = 0; i < layouts.size(); ++i) {
    const std::string lp = "structural.layouts[" + std::to_string(i) + "]";
    const YAML::Node l = r.mapping(layouts[i], lp);
    r.allowOnly(l, sc::kKeysLayout, lp);
    ObstacleLayout layout;
    r.string(l, "mesh_name", &layout.mesh_name, lp, true);
    const YAML::Node insts = l["instances"];
    if (insts && !insts.IsSequence()) {  // absent: none; null is refused, as in Python
      r.fail(lp + ".instances", "must be a list of instances");
    } else {
      for (size_t j = 0; insts && j < insts.size(); ++j) {
        const std::string ip = lp + ".instances[" + std::to_string(j) + "]";
        const YAML::Node n = r.mapping(insts[j], ip);
        r.allowOnly(n, sc::kKeysInstance, ip);
        ObstacleInstance inst;
        r.boolean(n, sc::kInstanceVisible, &inst.visible, ip);
        r.boolean(n, sc::kInstanceCastShadow, &inst.cast_shadow, ip);
        r.number(n, sc::kInstanceX, &inst.x, ip);
        r.number(n, sc::kInstanceY, &inst.y, ip);
        r.number(n, sc::kInstanceYaw, &inst.yaw, ip);
        r.number(n, sc::kInstanceScale, &inst.scale, ip);
        layout.instances.push_back(inst);
      }
    }
    out->push_back(layout);
  }
}

void readStructural(Reader& r, const YAML::Node& root, SceneSpec* s) {
  const YAML::Node st = r.mapping(root["structural"], "structural");
  r.allowOnly(st, sc::kKeysStructural, "structural");
  const std::string lp = "structural.landscape";
  const YAML::Node ld = r.mapping(st["landscape"], lp);
  r.allowOnly(ld, sc::kKeysLandscape, lp);
  r.number(ld, sc::kLandscapeSize, &s->landscape.size, lp);
  r.integer(ld, sc::kLandscapeSubdivisions, &s->landscape.subdivisions, lp);
  r.number(ld, sc::kLandscapeBorder, &s->landscape.border, lp);
  if (st["terrain"]) readTerrain(r, st["terrain"], &s->terrain);  // absent: flat; null is refused
  readLayouts(r, st["layouts"], &s->layouts);
}

void readTextural(Reader& r, const YAML::Node& root, Textural* t) {
  const std::string tp = "textural";
  const YAML::Node tx = r.mapping(root["textural"], tp);
  r.allowOnly(tx, sc::kKeysTextural, tp);
  r.number(tx, sc::kTexturalSunInclinationDeg, &t->sun_inclination_deg, tp);
  r.number(tx, sc::kTexturalSunYawDeg, &t->sun_yaw_deg, tp);
  r.integer(tx, sc::kTexturalGroundTextureSeed, &t->ground_texture_seed, tp);
  r.number(tx, sc::kTexturalFogVisibilityM, &t->fog_visibility_m, tp);
  r.number(tx, sc::kTexturalCloudCover, &t->cloud_cover, tp);
}

void readOperational(Reader& r, const YAML::Node& root, Operational* o) {
  const std::string ow = "operational";
  const YAML::Node op = r.mapping(root["operational"], ow);
  r.allowOnly(op, sc::kKeysOperational, ow);
  r.number(op, sc::kOperationalStartX, &o->start_x, ow);
  r.number(op, sc::kOperationalStartY, &o->start_y, ow);
  r.number(op, sc::kOperationalStartYaw, &o->start_yaw, ow);
  r.number(op, sc::kOperationalGoalX, &o->goal_x, ow);
  r.number(op, sc::kOperationalGoalY, &o->goal_y, ow);
  r.number(op, sc::kOperationalGoalRadius, &o->goal_radius, ow);
  r.number(op, sc::kOperationalSafetyRadius, &o->safety_radius, ow);
  r.number(op, sc::kOperationalSpeed, &o->speed, ow);
  r.number(op, sc::kOperationalSimTimeout, &o->sim_timeout, ow);
  r.number(op, sc::kOperationalIdleTimeout, &o->idle_timeout, ow);
  r.number(op, sc::kOperationalStuckTimeout, &o->stuck_timeout, ow);
  r.number(op, sc::kOperationalMaxRollDeg, &o->max_roll_deg, ow);
  r.number(op, sc::kOperationalMaxPitchDeg, &o->max_pitch_deg, ow);
  r.boolean(op, sc::kOperationalAllowCollisions, &o->allow_collisions, ow);
}

/// The parsed YAML of `path`, refused with the reason when it is not text YAML reads the way
/// the Python loader does (bad characters, a syntax error, a key given twice).
YAML::Node parseScenarioText(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw SceneError(path + ": cannot read the file");
  const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  std::string why;
  const size_t bad = firstBadCharacter(text, &why);
  if (bad != std::string::npos) {
    char buf[64];
    std::snprintf(buf, sizeof(buf), " (byte 0x%02x at offset %zu)", static_cast<unsigned char>(text[bad]), bad);
    throw SceneError(path + ": " + why + buf);
  }
  YAML::Node root;
  try {
    root = YAML::Load(text);
  } catch (const YAML::Exception& e) {
    throw SceneError(path + ": " + e.what());
  }
  const std::string dup = duplicateKey(root);
  if (!dup.empty()) throw SceneError(path + ": " + dup);
  return root;
}

}  // namespace

ScenarioFile loadScenarioYaml(const std::string& path) {
  const YAML::Node root = parseScenarioText(path);
  Reader r(path);
  if (!root.IsMap()) {
    r.fail("<root>", "must be a mapping of sections");
    r.raise();
  }
  ScenarioFile f;
  r.allowOnly(root, sc::kKeysTop, "");
  int version = 1;
  r.integer(root, sc::kTopFormatVersion, &version, "");
  r.integer(root, sc::kTopScenarioId, &f.scenario_id, "");
  r.boolean(root, sc::kTopRecordLabels, &f.record_labels, "");
  r.string(root, "name", &f.name, "", false);
  readStructural(r, root, &f.spec);
  readTextural(r, root, &f.spec.textural);
  readOperational(r, root, &f.spec.operational);
  r.raise();
  try {
    validateScene(f.spec);
  } catch (const SceneError& e) {
    throw SceneError(path + ": " + e.what());
  }
  return f;
}

}  // namespace asg_sim
