#include "harness/cases/case_document.hpp"

#include "lexdyn/common/error.hpp"

#include <algorithm>
#include <cctype>
#include <limits>

namespace lexdyn::cases {

Override parseOverride(const std::string& arg, const std::string& label_prefix) {
  const size_t eq = arg.find('=');
  const std::string label = label_prefix + " " + arg;
  if (eq == std::string::npos) throw InputError(label, "expected PATH=VALUE (e.g. controller.tasks[right_hand].gains.kp=0.5)");
  Override o;
  o.path = arg.substr(0, eq);
  o.value = arg.substr(eq + 1);
  o.label = label;
  auto blank = [](const std::string& s) { return std::all_of(s.begin(), s.end(), [](unsigned char c) { return std::isspace(c); }); };
  if (blank(o.path)) throw InputError(label, "empty key path");
  if (blank(o.value)) throw InputError(label, "empty value (give a YAML value: a number, a string, [a, b], {k: v})");
  return o;
}

std::string overrideText(const Override& o) { return o.path + "=" + o.value; }

namespace doc {

namespace {

// One step of a key path: a mapping key, or a sequence element by index or name.
struct Segment {
  std::string text;
  bool bracket = false;  ///< written as [text]
};

std::vector<Segment> split(const std::string& path, const std::string& where) {
  std::vector<Segment> out;
  size_t i = 0;
  std::string cur;
  auto flush = [&]() {
    if (!cur.empty()) out.push_back({cur, false});
    cur.clear();
  };
  while (i < path.size()) {
    const char c = path[i];
    if (c == '.') {
      if (cur.empty() && (out.empty() || !out.back().bracket)) throw InputError(where, "empty key in path '" + path + "'");
      flush();
      ++i;
    } else if (c == '[') {
      flush();
      const size_t close = path.find(']', i);
      if (close == std::string::npos) throw InputError(where, "unclosed '[' in path '" + path + "'");
      const std::string inner = path.substr(i + 1, close - i - 1);
      if (inner.empty()) throw InputError(where, "empty [] in path '" + path + "'");
      out.push_back({inner, true});
      i = close + 1;
      if (i < path.size() && path[i] != '.' && path[i] != '[')
        throw InputError(where, "expected '.' or '[' after ']' in path '" + path + "'");
      if (i < path.size() && path[i] == '.') {
        ++i;
        if (i == path.size()) throw InputError(where, "path '" + path + "' ends with '.'");
      }
    } else {
      cur += c;
      ++i;
    }
  }
  if (!cur.empty())
    flush();
  else if (!path.empty() && path.back() == '.')
    throw InputError(where, "path '" + path + "' ends with '.'");
  if (out.empty()) throw InputError(where, "empty key path");
  return out;
}

bool isIndex(const std::string& s) {
  return !s.empty() && s.size() < 10 && std::all_of(s.begin(), s.end(), [](unsigned char c) { return std::isdigit(c); });
}

std::string joinKey(const std::string& path, const std::string& key) { return path.empty() ? key : path + "." + key; }

/// The name an element goes by: its `name`, else its `match` (servo gain groups), else "".
std::string elementName(const YAML::Node& e) {
  if (!e.IsMap()) return "";
  for (const char* k : {"name", "match"}) {
    const YAML::Node n = e[k];
    if (n && n.IsScalar()) return n.Scalar();
  }
  return "";
}

size_t levenshtein(const std::string& a, const std::string& b) {
  std::vector<size_t> prev(b.size() + 1), cur(b.size() + 1);
  for (size_t j = 0; j <= b.size(); ++j) prev[j] = j;
  for (size_t i = 1; i <= a.size(); ++i) {
    cur[0] = i;
    for (size_t j = 1; j <= b.size(); ++j) {
      cur[j] = std::min({prev[j] + 1, cur[j - 1] + 1, prev[j - 1] + (a[i - 1] == b[j - 1] ? 0 : 1)});
    }
    std::swap(prev, cur);
  }
  return prev[b.size()];
}

// Every path of the document (display form), inner nodes and leaves.
void collect(const YAML::Node& n, const std::string& display, std::vector<std::string>& out) {
  if (!display.empty()) out.push_back(display);
  if (n.IsMap()) {
    for (auto it = n.begin(); it != n.end(); ++it) {
      if (it->first.IsScalar()) collect(it->second, joinKey(display, it->first.Scalar()), out);
    }
  } else if (n.IsSequence()) {
    for (size_t i = 0; i < n.size(); ++i) {
      const std::string name = elementName(n[i]);
      collect(n[i], display + "[" + (name.empty() ? std::to_string(i) : name) + "]", out);
    }
  }
}

// The three valid paths nearest to `path`: those below `prefix` (the part of the path that
// resolved) first, ranked by the edit distance of what follows it to `tail` (the rest of the
// path as given); then the others by the edit distance of the whole path.
std::string nearest(const YAML::Node& root, const Schema& schema, const std::string& path, const std::string& prefix,
                    const std::string& tail) {
  std::vector<std::string> candidates;
  collect(root, "", candidates);
  for (const std::string& k : schema.keys) {
    if (k.size() >= 2 && k.compare(k.size() - 2, 2, ".*") == 0) continue;
    candidates.push_back(displayPath(root, k));
  }
  std::sort(candidates.begin(), candidates.end());
  candidates.erase(std::unique(candidates.begin(), candidates.end()), candidates.end());
  auto below = [&](const std::string& c) {
    return !prefix.empty() && c.size() > prefix.size() && c.compare(0, prefix.size(), prefix) == 0 &&
           (c[prefix.size()] == '.' || c[prefix.size()] == '[');
  };
  std::vector<std::pair<std::pair<int, size_t>, std::string>> scored;
  // Edit distance, where a candidate that extends the text as typed (limit -> limit_fraction)
  // counts as one edit.
  auto distance = [](const std::string& typed, const std::string& c) {
    const size_t d = levenshtein(typed, c);
    if (c.size() <= typed.size()) return d;
    return std::min(d, levenshtein(typed, c.substr(0, typed.size())) + 1);
  };
  for (const auto& c : candidates) {
    if (below(c))
      scored.push_back({{0, distance(tail, c.substr(prefix.size() + 1))}, c});
    else
      scored.push_back({{1, distance(path, c)}, c});
  }
  std::stable_sort(scored.begin(), scored.end(), [](const auto& a, const auto& b) { return a.first < b.first; });
  std::string s;
  for (size_t i = 0; i < scored.size() && i < 3; ++i) s += (i ? ", " : "") + scored[i].second;
  return s;
}

std::string keysOf(const YAML::Node& map) {
  std::string s;
  for (auto it = map.begin(); it != map.end(); ++it) s += (s.empty() ? "" : ", ") + it->first.as<std::string>("?");
  return s;
}

struct Walk {
  Resolved r;
  YAML::Node parent;     ///< the mapping or sequence holding the last segment
  std::string last_key;  ///< the last mapping key ("" for a sequence element)
  long last_index = -1;  ///< the last sequence index
  size_t created = 0;    ///< absent segments at the end (a key path to create)
};

// Walks `path` through `root`; absent mapping keys are allowed where the schema knows them (or
// below a key being created). Throws with the nearest valid paths otherwise.
Walk walk(const YAML::Node& root, const std::string& path, const Schema& schema, const std::string& where) {
  const std::vector<Segment> segs = split(path, where);
  Walk w;
  YAML::Node cur = root;
  std::string canonical, display;
  bool absent = false;
  for (size_t s = 0; s < segs.size(); ++s) {
    const Segment& seg = segs[s];
    const std::string resolved = display;  // the part of the path that resolved
    auto fail = [&](const std::string& what) {
      std::string tail;
      for (size_t k = s; k < segs.size(); ++k) tail += (k > s ? "." : "") + segs[k].text;
      throw InputError(where, what + "; nearest valid paths: " + nearest(root, schema, path, resolved, tail));
    };
    if (absent) {  // below a key that does not exist yet: nothing to check against
      canonical = joinKey(canonical, seg.text);
      display = joinKey(display, seg.text);
      w.last_key = seg.text;
      ++w.created;
      continue;
    }
    if (cur.IsSequence()) {
      long index = -1;
      if (isIndex(seg.text)) {
        index = std::stol(seg.text);
        if (index >= static_cast<long>(cur.size())) {
          fail("'" + (display.empty() ? seg.text : display) + "' has " + std::to_string(cur.size()) + " elements, no element " + seg.text);
        }
      } else {
        std::string names;
        for (size_t i = 0; i < cur.size(); ++i) {
          const std::string n = elementName(cur[i]);
          if (n == seg.text) index = static_cast<long>(i);
          if (!n.empty()) names += (names.empty() ? "" : ", ") + n;
        }
        if (index < 0)
          fail("'" + display + "' has no element named '" + seg.text + "'" + (names.empty() ? "" : " (elements: " + names + ")"));
      }
      const std::string name = elementName(cur[static_cast<size_t>(index)]);
      canonical += "[" + std::to_string(index) + "]";
      display += "[" + (name.empty() ? std::to_string(index) : name) + "]";
      w.parent.reset(cur);
      w.last_key.clear();
      w.last_index = index;
      const YAML::Node element = static_cast<const YAML::Node&>(cur)[static_cast<size_t>(index)];
      cur.reset(element);
      continue;
    }
    if (!cur.IsMap()) {
      fail("'" + display + "' is a value (" + (cur.IsScalar() ? "'" + cur.Scalar() + "'" : std::string("null")) + "), it has no key '" +
           seg.text + "'");
    }
    const std::string next = joinKey(canonical, seg.text);
    const YAML::Node child = static_cast<const YAML::Node&>(cur)[seg.text];
    w.parent.reset(cur);
    w.last_key = seg.text;
    w.last_index = -1;
    canonical = next;
    display = joinKey(display, seg.text);
    if (child) {
      cur.reset(child);
      continue;
    }
    if (!schema.knows(next)) {
      fail("no key '" + seg.text + "' in " + (resolved.empty() ? std::string("the case") : "'" + resolved + "'") +
           " (keys there: " + keysOf(cur) + ")");
    }
    absent = true;
    w.created = 1;
  }
  w.r.canonical = canonical;
  w.r.display = display;
  w.r.exists = !absent;
  if (!absent) w.r.node.reset(cur);
  return w;
}

}  // namespace

bool Schema::knows(const std::string& canonical) const {
  if (std::find(keys.begin(), keys.end(), canonical) != keys.end()) return true;
  const size_t dot = canonical.rfind('.');
  if (dot == std::string::npos) return false;
  const std::string free = canonical.substr(0, dot) + ".*";
  return std::find(keys.begin(), keys.end(), free) != keys.end();
}

std::string displayPath(const YAML::Node& root, const std::string& canonical) {
  std::string out;
  YAML::Node cur = root;
  bool lost = false;
  size_t i = 0;
  while (i < canonical.size()) {
    if (canonical[i] == '[') {
      const size_t close = canonical.find(']', i);
      const std::string idx = canonical.substr(i + 1, close - i - 1);
      std::string name;
      if (!lost && cur.IsSequence() && isIndex(idx) && std::stoul(idx) < cur.size()) {
        const YAML::Node element = static_cast<const YAML::Node&>(cur)[std::stoul(idx)];
        cur.reset(element);
        name = elementName(cur);
      } else {
        lost = true;
      }
      out += "[" + (name.empty() ? idx : name) + "]";
      i = close + 1;
      continue;
    }
    if (canonical[i] == '.') {
      out += '.';
      ++i;
      continue;
    }
    size_t end = canonical.find_first_of(".[", i);
    if (end == std::string::npos) end = canonical.size();
    const std::string key = canonical.substr(i, end - i);
    out += key;
    const YAML::Node child = cur.IsMap() ? static_cast<const YAML::Node&>(cur)[key] : YAML::Node();
    if (!lost && child)
      cur.reset(child);
    else
      lost = true;
    i = end;
  }
  return out;
}

Resolved resolve(const YAML::Node& root, const std::string& path, const Schema& schema, const std::string& where) {
  return walk(root, path, schema, where).r;
}

Resolved set(YAML::Node& root, const std::string& path, const YAML::Node& value, const Schema& schema, const std::string& where) {
  Walk w = walk(root, path, schema, where);
  if (w.r.exists) {
    if (w.last_index >= 0)
      w.parent[static_cast<size_t>(w.last_index)] = value;
    else
      w.parent[w.last_key] = value;
    w.r.node.reset(value);
    return w.r;
  }
  // Create the absent keys: mappings down to the last one, which takes the value.
  const std::vector<Segment> segs = split(path, where);
  YAML::Node cur = w.parent;
  for (size_t s = segs.size() - w.created; s < segs.size(); ++s) {
    if (s + 1 == segs.size()) {
      cur[segs[s].text] = value;
    } else {
      cur[segs[s].text] = YAML::Node(YAML::NodeType::Map);
      const YAML::Node created = static_cast<const YAML::Node&>(cur)[segs[s].text];
      cur.reset(created);
    }
  }
  w.r.node.reset(value);
  return w.r;
}

YAML::Node parseValue(const Override& o) {
  try {
    return YAML::Load(o.value);
  } catch (const YAML::Exception& e) {
    throw InputError(o.label, "the value is not valid YAML: " + e.msg);
  }
}

std::string relabel(const Document& d, const std::string& where) {
  // where: "file:line: key.path" or "file: key.path"; the key path follows the last ": ".
  const size_t sep = where.rfind(": ");
  if (sep == std::string::npos) return where;
  const std::string path = where.substr(sep + 2);
  for (size_t i = d.overrides.size(); i-- > 0;) {
    const std::string& c = d.canonical[i];
    const bool below = path.size() > c.size() && path.compare(0, c.size(), c) == 0 && (path[c.size()] == '.' || path[c.size()] == '[');
    if (path == c || below) return d.overrides[i].label + (path == c ? "" : " (" + displayPath(d.root, path) + ")");
  }
  return where;
}

std::string emit(const YAML::Node& root) {
  YAML::Emitter out;
  out.SetIndent(2);
  out << root;
  return std::string(out.c_str()) + "\n";
}

}  // namespace doc

}  // namespace lexdyn::cases
