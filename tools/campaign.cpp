#include "campaign.hpp"

#include <algorithm>
#include <filesystem>
#include <functional>
#include <numeric>
#include <set>
#include <sstream>

namespace mesopen {

namespace fs = std::filesystem;

namespace {

// What a [[run]] entry holds besides scene tables.
const std::set<std::string> run_fields = {"name", "label", "scene", "reference"};
const std::set<std::string> trend_fields = {"name", "measure", "expect", "runs", "x", "tolerance"};
const std::set<std::string> campaign_fields = {"name",       "base",        "representation",
                                               "replicates", "seed_stride", "frames"};

// Sets every key of `over` into `into`, table by table.
void merge(toml::table &into, const toml::table &over) {
  for (const auto &[key, node] : over) {
    const toml::table *sub = node.as_table();
    toml::table *there = into.get_as<toml::table>(key);
    if (sub && there)
      merge(*there, *sub);
    else
      into.insert_or_assign(key, node);
  }
}

bool isMeasure(const std::string &name) {
  return std::any_of(std::begin(campaign_measures), std::end(campaign_measures),
                     [&](const CampaignMeasure &m) { return name == m.name; });
}

std::string measureNames() {
  std::string s;
  for (const auto &m : campaign_measures)
    s += (s.empty() ? "\"" : ", \"") + std::string(m.name) + "\"";
  return s;
}

} // namespace

Campaign readCampaign(const std::string &path) {
  const toml::table root = parseToml(path);
  Campaign c;
  c.path = path;
  auto bad = [&](const std::string &what) -> InputError { return InputError(path + ": " + what); };
  // A string value, or the default when the key is absent; any other type is bad input.
  auto string = [&](const toml::table &t, const char *key, const std::string &where,
                    const std::string &fallback) {
    const toml::node *n = t.get(key);
    if (!n)
      return fallback;
    if (!n->is_string())
      throw bad(where + key + " = " + tomlText(*n) + " is not a string");
    return n->value_or(std::string());
  };
  for (const auto &[key, node] : root)
    if (key != "campaign" && key != "run" && key != "trend")
      throw bad("unknown table [" + std::string(key.str()) +
                "]; known: [campaign], [[run]], [[trend]]");
  const fs::path dir = fs::path(path).parent_path();
  auto file = [&](const std::string &name) { return (dir / name).lexically_normal().string(); };

  std::string base;
  if (root.get("campaign") && !root["campaign"].is_table())
    throw bad("campaign must be a table ([campaign])");
  if (const toml::table *t = root["campaign"].as_table()) {
    for (const auto &[key, node] : *t)
      if (!campaign_fields.count(std::string(key.str())))
        throw bad("unknown key campaign." + std::string(key.str()) +
                  "; known: name, base, representation, replicates, seed_stride, frames");
    c.name = string(*t, "name", "campaign.", "");
    if (const std::string b = string(*t, "base", "campaign.", ""); !b.empty())
      base = file(b);
    if (const toml::node *r = t->get("representation")) {
      c.representation = valueOf(r->value_or(std::string()), representation_names);
      if (!c.representation)
        throw bad("campaign.representation = " + tomlText(*r) +
                  " is not known; allowed: one of "
                  "\"fe\", \"dem\", \"hybrid\"");
    }
    if (const toml::node *r = t->get("replicates")) {
      const auto n = r->value<std::int64_t>();
      if (!n || *n < 1 || *n > 1000)
        throw bad("campaign.replicates = " + tomlText(*r) +
                  " is out of range; allowed: an integer, "
                  "1 <= replicates <= 1000");
      c.replicates = static_cast<int>(*n);
    }
    if (const toml::node *r = t->get("seed_stride")) {
      const auto n = r->value<std::int64_t>();
      if (!n || *n < 1 || *n > 1000000000)
        throw bad("campaign.seed_stride = " + tomlText(*r) +
                  " is out of range; allowed: an integer, "
                  "1 <= seed_stride <= 1e9");
      c.seed_stride = *n;
    }
    if (const toml::node *f = t->get("frames")) {
      if (!f->is_boolean())
        throw bad("campaign.frames = " + tomlText(*f) +
                  " is not a boolean; allowed: true or false");
      c.frames = f->value_or(false);
    }
  }

  const toml::array *runs = root["run"].as_array();
  if (!runs || runs->empty())
    throw bad("no [[run]]: a campaign needs at least one run");
  std::set<std::string> names;
  for (std::size_t i = 0; i < runs->size(); ++i) {
    const toml::table *t = (*runs)[i].as_table();
    const std::string where = "run " + std::to_string(i + 1);
    if (!t)
      throw bad(where + " is not a table ([[run]])");
    CampaignRun r;
    const auto name = (*t)["name"].value<std::string>();
    if (!name || name->empty() ||
        !std::all_of(name->begin(), name->end(),
                     [](char ch) {
                       return std::isalnum(static_cast<unsigned char>(ch)) || ch == '-' ||
                              ch == '_' || ch == '.';
                     }) ||
        (*name)[0] == '.')
      throw bad(where + ": name = " + ((*t)["name"] ? tomlText(*t->get("name")) : "(none)") +
                " is not allowed; allowed: a name of letters, digits, '-', '_' and '.' (it names "
                "the run's directory)");
    r.name = *name;
    if (!names.insert(r.name).second)
      throw bad("two runs are named \"" + r.name + "\"");
    r.label = string(*t, "label", "run \"" + r.name + "\": ", "");
    if (const std::string scene = string(*t, "scene", "run \"" + r.name + "\": ", "");
        !scene.empty())
      r.scene = file(scene);
    else if (!base.empty())
      r.scene = base;
    else
      throw bad("run \"" + r.name +
                "\" has no scene, and the campaign no base; allowed: "
                "scene = \"FILE\" in the run or base = \"FILE\" in [campaign]");
    if (!fs::is_regular_file(r.scene))
      throw bad("run \"" + r.name + "\": scene " + r.scene + " not found");
    if (t->get("reference") && !(*t)["reference"].is_table())
      throw bad("run \"" + r.name +
                "\": reference must be a table, e.g. reference = "
                "{ average_lateral_force = 2950 }");
    if (const toml::table *ref = (*t)["reference"].as_table())
      for (const auto &[key, node] : *ref) {
        const auto v = node.value<double>();
        if (!isMeasure(std::string(key.str())) || !v)
          throw bad("run \"" + r.name + "\": reference." + std::string(key.str()) + " = " +
                    tomlText(node) + " is not allowed; allowed: numbers for " + measureNames());
        r.reference[std::string(key.str())] = *v;
      }
    for (const auto &[key, node] : *t)
      if (!run_fields.count(std::string(key.str())))
        r.set.insert_or_assign(key, node);
    c.runs.push_back(std::move(r));
  }

  if (const toml::node *trends = root.get("trend")) {
    const toml::array *list = trends->as_array();
    if (!list)
      throw bad("trend must be an array of tables ([[trend]])");
    for (std::size_t i = 0; i < list->size(); ++i) {
      const toml::table *t = (*list)[i].as_table();
      const std::string where = "trend " + std::to_string(i + 1);
      if (!t)
        throw bad(where + " is not a table ([[trend]])");
      for (const auto &[key, node] : *t)
        if (!trend_fields.count(std::string(key.str())))
          throw bad(where + ": unknown key " + std::string(key.str()) +
                    "; known: name, measure, expect, runs, x");
      Trend tr;
      tr.name = string(*t, "name", where + ": ", where);
      tr.measure = string(*t, "measure", where + ": ", tr.measure);
      if (!isMeasure(tr.measure))
        throw bad(where + ": measure = \"" + tr.measure + "\" is not known; allowed: one of " +
                  measureNames());
      const auto expect = (*t)["expect"].value<std::string>();
      const auto kind = valueOf(expect.value_or(""), trend_kind_names);
      if (!kind)
        throw bad(where +
                  ": expect = " + (t->get("expect") ? tomlText(*t->get("expect")) : "(none)") +
                  " is not known; allowed: one of \"rises\", \"falls\", \"differs\", \"similar\"");
      tr.expect = *kind;
      if (const toml::array *rs = (*t)["runs"].as_array())
        for (const auto &n : *rs) {
          if (!n.is_string())
            throw bad(where + ": runs holds " + tomlText(n) + "; allowed: names of runs (strings)");
          tr.runs.push_back(n.value_or(std::string()));
        }
      for (std::size_t k = 0; k < tr.runs.size(); ++k) {
        if (!names.count(tr.runs[k]))
          throw bad(where + ": runs holds \"" + tr.runs[k] + "\", which is no run of the campaign");
        if (std::count(tr.runs.begin(), tr.runs.begin() + k, tr.runs[k]))
          throw bad(where + ": runs names \"" + tr.runs[k] + "\" twice");
      }
      if (tr.runs.size() < 2 || (tr.expect == TrendKind::differs && tr.runs.size() != 2))
        throw bad(where + ": runs must name " +
                  (tr.expect == TrendKind::differs ? std::string("exactly 2") : "at least 2") +
                  " runs of the campaign");
      if (const toml::array *xs = (*t)["x"].as_array()) {
        for (const auto &n : *xs)
          if (auto v = n.value<double>())
            tr.x.push_back(*v);
        if (tr.x.size() != xs->size() || tr.x.size() != tr.runs.size() ||
            tr.expect == TrendKind::differs || tr.expect == TrendKind::similar ||
            std::adjacent_find(tr.x.begin(), tr.x.end(), std::greater_equal<double>()) !=
                tr.x.end())
          throw bad(where +
                    ": x must give one number per run, increasing, for rises or falls only");
      } else {
        for (std::size_t k = 0; k < tr.runs.size(); ++k)
          tr.x.push_back(static_cast<double>(k + 1));
      }
      if (const toml::node *tol = t->get("tolerance")) {
        const auto v = tol->value<double>();
        if (!v || !(*v > 0.0) || *v > 100.0 || tr.expect != TrendKind::similar)
          throw bad(where + ": tolerance = " + tomlText(*tol) +
                    " is not allowed; allowed: a number, "
                    "0 < tolerance <= 100, for expect = \"similar\" only");
        tr.tolerance = *v;
      }
      if (tr.expect == TrendKind::similar && std::isnan(tr.tolerance))
        throw bad(where + ": expect = \"similar\" needs tolerance (the largest difference that "
                          "counts as alike, a fraction of the runs' mean, e.g. 0.5)");
      c.trends.push_back(std::move(tr));
    }
  }

  // Every run's scene, composed and read now: a bad key stops the campaign before it starts.
  for (const CampaignRun &r : c.runs) {
    std::istringstream in(composeScene(c, r, 0));
    try {
      readScene(toml::parse(in, r.scene),
                path + ", run \"" + r.name + "\" (scene " + r.scene + ")");
    } catch (const toml::parse_error &e) {
      throw bad("run \"" + r.name + "\": " + std::string(e.description()));
    }
  }
  return c;
}

std::string composeScene(const Campaign &campaign, const CampaignRun &run, int replicate) {
  toml::table scene = parseToml(run.scene);
  merge(scene, run.set);
  auto table = [&](const char *name) -> toml::table & {
    if (!scene.get_as<toml::table>(name))
      scene.insert_or_assign(name, toml::table{});
    return *scene.get_as<toml::table>(name);
  };
  // (a seed that is no integer is left for readScene to report)
  if (!table("target").get("seed") || table("target")["seed"].is_integer()) {
    const auto seed =
        table("target")["seed"].value_or(static_cast<std::int64_t>(TargetSpec{}.seed));
    table("target").insert_or_assign("seed", seed + replicate * campaign.seed_stride);
  }
  if (campaign.representation)
    table("run").insert_or_assign(
        "representation", std::string(nameOf(*campaign.representation, representation_names)));
  if (!campaign.frames)
    table("run").insert_or_assign("frame_interval", 0.0);
  std::ostringstream out;
  out << "# Run \"" << run.name << "\" of a campaign, replicate " << replicate + 1 << ": "
      << fs::path(run.scene).filename().string() << " with the campaign's keys\n"
      << scene << "\n";
  return out.str();
}

double studentT95(int dof) {
  // Two-sided 95 % (0.975 quantile), dof 1-30 (standard tables); beyond, the Cornish-Fisher
  // expansion about the normal quantile, within 1e-4 of the exact value from dof 30 on.
  static const double table[] = {12.7062, 4.3027, 3.1824, 2.7764, 2.5706, 2.4469, 2.3646, 2.3060,
                                 2.2622,  2.2281, 2.2010, 2.1788, 2.1604, 2.1448, 2.1314, 2.1199,
                                 2.1098,  2.1009, 2.0930, 2.0860, 2.0796, 2.0739, 2.0687, 2.0639,
                                 2.0595,  2.0555, 2.0518, 2.0484, 2.0452, 2.0423};
  if (dof < 1)
    return NAN;
  if (dof <= 30)
    return table[dof - 1];
  const double z = 1.959964, n = dof;
  return z + (z * z * z + z) / (4 * n) +
         (5 * std::pow(z, 5) + 16 * z * z * z + 3 * z) / (96 * n * n) +
         (3 * std::pow(z, 7) + 19 * std::pow(z, 5) + 17 * z * z * z - 15 * z) / (384 * n * n * n);
}

Estimate estimate(const std::vector<double> &values) {
  Estimate e;
  e.n = static_cast<int>(values.size());
  if (e.n == 0)
    return e;
  e.mean = std::accumulate(values.begin(), values.end(), 0.0) / e.n;
  if (e.n < 2)
    return e;
  double ss = 0.0;
  for (double v : values)
    ss += (v - e.mean) * (v - e.mean);
  e.sd = std::sqrt(ss / (e.n - 1));
  e.half_width = studentT95(e.n - 1) * e.sd / std::sqrt(e.n);
  return e;
}

namespace {

// Least-squares slope of y against x with the half-width of its 95 % interval.
std::pair<double, double> slopeOf(const std::vector<double> &x, const std::vector<double> &y) {
  const std::size_t n = x.size();
  const double mx = std::accumulate(x.begin(), x.end(), 0.0) / n;
  const double my = std::accumulate(y.begin(), y.end(), 0.0) / n;
  double sxx = 0.0, sxy = 0.0;
  for (std::size_t i = 0; i < n; ++i)
    sxx += (x[i] - mx) * (x[i] - mx), sxy += (x[i] - mx) * (y[i] - my);
  const double b = sxy / sxx;
  double sse = 0.0;
  for (std::size_t i = 0; i < n; ++i)
    sse += std::pow(y[i] - my - b * (x[i] - mx), 2);
  const int dof = static_cast<int>(n) - 2;
  return {b, dof >= 1 ? studentT95(dof) * std::sqrt(sse / dof / sxx) : NAN};
}

} // namespace

TrendResult testTrend(const Trend &trend, const std::vector<std::vector<double>> &values) {
  TrendResult r;
  auto magnitudes = [&](std::size_t k) {
    std::vector<double> m;
    for (double v : values[k])
      m.push_back(std::abs(v));
    return m;
  };
  auto pair = [&](std::size_t a, std::size_t b, double xa, double xb) {
    std::vector<double> x, y;
    for (std::size_t k : {a, b})
      for (double v : magnitudes(k))
        x.push_back(k == a ? xa : xb), y.push_back(v);
    return slopeOf(x, y);
  };
  std::vector<double> means;
  for (std::size_t k = 0; k < values.size(); ++k) {
    r.magnitudes.push_back(estimate(magnitudes(k)));
    means.push_back(r.magnitudes.back().mean);
  }
  const bool up = std::is_sorted(means.begin(), means.end());
  const bool down = std::is_sorted(means.rbegin(), means.rend());
  r.seen = std::any_of(means.begin(), means.end(), [](double m) { return std::isnan(m); }) ? "n/a"
           : means.back() > means.front() ? (up ? "rises" : "rises overall")
           : means.back() < means.front() ? (down ? "falls" : "falls overall")
                                          : "flat";
  const bool replicated = std::all_of(values.begin(), values.end(),
                                      [](const std::vector<double> &v) { return v.size() >= 2; });
  switch (trend.expect) {
  case TrendKind::rises:
  case TrendKind::falls: {
    std::vector<double> x, y;
    for (std::size_t k = 0; k < values.size(); ++k)
      for (double v : magnitudes(k))
        x.push_back(trend.x[k]), y.push_back(v);
    std::tie(r.effect, r.half_width) = slopeOf(x, y);
    const double sign = trend.expect == TrendKind::rises ? 1.0 : -1.0;
    r.verdict = !replicated || std::isnan(r.half_width) ? "not tested"
                : sign * r.effect - r.half_width > 0.0  ? "confirmed"
                : sign * r.effect + r.half_width < 0.0  ? "reversed"
                                                        : "not confirmed";
    break;
  }
  case TrendKind::differs:
    std::tie(r.effect, r.half_width) = pair(0, 1, 0.0, 1.0);
    r.verdict = !replicated || std::isnan(r.half_width)   ? "not tested"
                : std::abs(r.effect) - r.half_width > 0.0 ? "confirmed"
                                                          : "not confirmed";
    break;
  case TrendKind::similar: {
    const double margin = trend.tolerance * estimate(means).mean;
    bool within = true, beyond = false;
    double farthest = -1.0;
    for (std::size_t a = 0; a < values.size(); ++a)
      for (std::size_t b = a + 1; b < values.size(); ++b) {
        const auto [d, h] = pair(a, b, 0.0, 1.0);
        if (std::abs(d) + h > farthest)
          farthest = std::abs(d) + h, r.effect = d, r.half_width = h;
        within = within && std::abs(d) + h <= margin;
        beyond = beyond || std::abs(d) - h > margin;
      }
    r.verdict = !replicated || std::isnan(r.half_width) ? "not tested"
                : within                                ? "confirmed"
                : beyond                                ? "reversed"
                                                        : "not confirmed";
    break;
  }
  }
  return r;
}

} // namespace mesopen
