// Sharded bakes. A shard runs the whole pipeline with a TraceLog (trace_log.h): the phases
// before its own are replayed from every shard's parts, its phase's tracing calls are traced
// for its slice of their points only, and at the phase's barrier it stops and writes what it
// traced. The merge replays every phase and runs what follows the last one (the fit). Seeds
// are per point (each vertex's and each sample's stream), never per thread or shard, so the
// merged asset is bit-identical to one process's, whatever the shard count.
//
// A part file: a text header (what it is, the bake's key, shard, phase, notes, and one line per
// tracing call: fingerprint, points, slice, values per point, rays), "end", then the slices'
// values and variances as little-endian doubles, and an XXH3 checksum of them in the header.
// Every size is checked against the file before anything is read into memory.
#include "prtsub/prt/shard.h"

#include <algorithm>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>

#include <xxhash.h>

#include "prtsub/prt/output_file.h"
#include "prtsub/prt/trace_log.h"
#include "prtsub/subdiv/exceptions.h"
#include "prtsub/subdiv/ply.h"
#include "prtsub/subdiv/stopwatch.h"

namespace fs = std::filesystem;

namespace prtsub {

std::pair<uint32_t, uint32_t> parse_shard(const std::string& text) {
  const size_t slash = text.find('/');
  auto number = [&](const std::string& s) -> long {
    if (s.empty() || s.size() > 6 || s.find_first_not_of("0123456789") != std::string::npos) return -1;
    return std::stol(s);
  };
  const long i = slash == std::string::npos ? -1 : number(text.substr(0, slash));
  const long n = slash == std::string::npos ? -1 : number(text.substr(slash + 1));
  if (i < 1 || n < 1 || i > n || n > 65536) throw InputError("--shard takes I/N with 1 <= I <= N <= 65536, not '" + text + "'");
  return {uint32_t(i), uint32_t(n)};
}

int shard_phases(const BakeOptions& in) {
  const BakeOptions o = resolve_bake_options(in);
  // The vertices' early-stop rounds each end a phase, then the pilot's stages do.
  const int early = early_stop_on(o) ? early_stop_rounds(o.round_rays, o.transfer.rays) : 0;
  if (o.fit.method == FitMethod::Point) return 1 + early;
  if (o.allocation != SampleAllocation::Pilot || o.pilot.rays < 2) return 1 + early;
  const int screen = o.pilot.screen_ratio > 0 && o.pilot.holdout > 0 ? 1 : 0;
  return (o.pilot.first_share > 0 && o.pilot.first_share < 1 ? 3 : 2) + screen + early;
}

namespace {

constexpr const char* kMagic = "prtsub part 1";

std::string part_name(uint32_t phase, uint32_t shard, uint32_t shards) {
  return "phase" + std::to_string(phase) + "-shard" + std::to_string(shard) + "of" + std::to_string(shards) + ".part";
}

struct CallLine {
  uint64_t fingerprint = 0, points = 0, first = 0, last = 0;
  uint32_t k = 0;
  int rays = 0;
};

struct ParsedHeader {
  PartHeader header;
  std::vector<CallLine> calls;
  uint64_t checksum = 0;
  size_t payload_offset = 0;
};

uint64_t parse_u64(const std::string& s, const std::string& path, const char* what, int base = 10) {
  if (s.empty() || s.size() > 20) throw InputError(path + ": not a prtsub part (bad " + what + ")");
  size_t used = 0;
  uint64_t v = 0;
  try {
    v = std::stoull(s, &used, base);
  } catch (const std::exception&) {
    used = 0;
  }
  if (used != s.size() || s[0] == '-' || s[0] == '+') throw InputError(path + ": not a prtsub part (bad " + what + ")");
  return v;
}

// The header, read line by line (at most 1 MiB of it), then checked for sense.
ParsedHeader parse_header(std::istream& in, const std::string& path) {
  ParsedHeader p;
  p.header.path = path;
  std::string line;
  size_t read = 0;
  bool magic = false, ended = false, have_sum = false;
  while (std::getline(in, line)) {
    read += line.size() + 1;
    if (read > (1u << 20)) throw InputError(path + ": not a prtsub part (its header runs past 1 MiB)");
    if (!magic) {
      if (line != kMagic) throw InputError(path + ": not a prtsub part (it does not start with '" + std::string(kMagic) + "')");
      magic = true;
      continue;
    }
    if (line == "end") {
      ended = true;
      break;
    }
    const size_t sp = line.find(' ');
    const std::string name = line.substr(0, sp), value = sp == std::string::npos ? "" : line.substr(sp + 1);
    if (name == "key") p.header.key = value;
    else if (name == "shard") p.header.shard = uint32_t(std::min<uint64_t>(parse_u64(value, path, "shard"), UINT32_MAX));
    else if (name == "shards") p.header.shards = uint32_t(std::min<uint64_t>(parse_u64(value, path, "shards"), UINT32_MAX));
    else if (name == "phase") p.header.phase = uint32_t(std::min<uint64_t>(parse_u64(value, path, "phase"), UINT32_MAX));
    else if (name == "checksum") p.checksum = parse_u64(value, path, "checksum", 16), have_sum = true;
    else if (name == "note") {
      const size_t s2 = value.find(' ');
      p.header.notes.push_back({value.substr(0, s2), s2 == std::string::npos ? "" : value.substr(s2 + 1)});
    } else if (name == "call") {
      std::istringstream f(value);
      std::string a[6];
      for (std::string& x : a) f >> x;
      CallLine c;
      c.fingerprint = parse_u64(a[0], path, "call", 16), c.points = parse_u64(a[1], path, "call");
      c.first = parse_u64(a[2], path, "call"), c.last = parse_u64(a[3], path, "call");
      const uint64_t k = parse_u64(a[4], path, "call"), rays = parse_u64(a[5], path, "call");
      if (c.first > c.last || c.last > c.points || c.points > (uint64_t(1) << 40) || k < 1 || k > 100 || rays < 1 || rays > (1u << 30))
        throw InputError(path + ": not a prtsub part (a call's slice or size is out of range)");
      c.k = uint32_t(k), c.rays = int(rays);
      p.calls.push_back(c);
    } else {
      throw InputError(path + ": not a prtsub part (unknown header line '" + name + "')");
    }
  }
  if (!magic) throw InputError(path + ": not a prtsub part (empty)");
  if (!ended) throw InputError(path + ": not a prtsub part (its header has no end: cut short?)");
  const PartHeader& h = p.header;
  if (h.key.empty() || h.shards == 0 || h.shard == 0 || h.shard > h.shards || h.phase == 0 || h.phase > 64 || !have_sum)
    throw InputError(path + ": not a prtsub part (its key, shard, phase or checksum is missing or out of range)");
  p.payload_offset = read;
  return p;
}

ParsedHeader open_header(const std::string& path, std::ifstream& in) {
  in.open(path, std::ios::binary);
  if (!in) throw IoError(path + ": cannot open");
  return parse_header(in, path);
}

// A part's calls' slices from `in` (just past the header), the payload checked against the
// part's size and its checksum.
std::vector<TraceCall> read_calls(std::istream& in, const ParsedHeader& p, uint64_t size, const std::string& path) {
  uint64_t doubles = 0;
  for (const CallLine& c : p.calls) doubles += (c.last - c.first) * (uint64_t(c.k) + 1);
  if (size != p.payload_offset + doubles * sizeof(double))
    throw InputError(path + ": damaged part: " + std::to_string(size) + " bytes where its header says " +
                     std::to_string(p.payload_offset + doubles * sizeof(double)));
  std::vector<TraceCall> calls;
  XXH3_state_t* state = XXH3_createState();
  if (!state) throw Error("shard: cannot allocate a hash state");
  XXH3_64bits_reset(state);
  for (const CallLine& l : p.calls) {
    TraceCall c;
    c.fingerprint = l.fingerprint, c.points = l.points, c.first = l.first, c.last = l.last, c.values_per_point = l.k, c.rays = l.rays;
    c.values.resize(size_t(l.last - l.first) * l.k), c.variance.resize(size_t(l.last - l.first));
    in.read(reinterpret_cast<char*>(c.values.data()), std::streamsize(c.values.size() * sizeof(double)));
    in.read(reinterpret_cast<char*>(c.variance.data()), std::streamsize(c.variance.size() * sizeof(double)));
    XXH3_64bits_update(state, c.values.data(), c.values.size() * sizeof(double));
    XXH3_64bits_update(state, c.variance.data(), c.variance.size() * sizeof(double));
    calls.push_back(std::move(c));
  }
  const uint64_t sum = XXH3_64bits_digest(state);
  XXH3_freeState(state);
  if (!in) throw IoError(path + ": cannot read its values");
  if (sum != p.checksum) throw InputError(path + ": damaged part: its values do not match its checksum");
  return calls;
}

std::vector<TraceCall> read_part_calls(const std::string& path) {
  std::ifstream in;
  const ParsedHeader p = open_header(path, in);
  std::error_code ec;
  const uint64_t size = fs::file_size(path, ec);
  if (ec) throw IoError(path + ": cannot read its size (" + ec.message() + ")");
  return read_calls(in, p, size, path);
}

void write_part(const std::string& path, const PartHeader& h, const std::vector<TraceCall>& calls) {
  std::string payload;
  XXH3_state_t* state = XXH3_createState();
  if (!state) throw Error("shard: cannot allocate a hash state");
  XXH3_64bits_reset(state);
  for (const TraceCall& c : calls) {
    if (c.values.size() != (c.last - c.first) * c.values_per_point || c.variance.size() != c.last - c.first)
      throw Error("shard: a traced slice has the wrong size");
    const char* v = reinterpret_cast<const char*>(c.values.data());
    const char* w = reinterpret_cast<const char*>(c.variance.data());
    payload.append(v, c.values.size() * sizeof(double));
    payload.append(w, c.variance.size() * sizeof(double));
    XXH3_64bits_update(state, v, c.values.size() * sizeof(double));
    XXH3_64bits_update(state, w, c.variance.size() * sizeof(double));
  }
  const uint64_t sum = XXH3_64bits_digest(state);
  XXH3_freeState(state);
  std::ostringstream s;
  char hex[40];
  s << kMagic << "\nkey " << h.key << "\nshards " << h.shards << "\nshard " << h.shard << "\nphase " << h.phase << "\n";
  for (const auto& [name, value] : h.notes) {
    if (name.empty() || name.find_first_of(" \n") != std::string::npos || value.find('\n') != std::string::npos)
      throw InputError("shard: a note must be one word and one line ('" + name + "')");
    s << "note " << name << " " << value << "\n";
  }
  for (const TraceCall& c : calls) {
    std::snprintf(hex, sizeof hex, "%016llx", static_cast<unsigned long long>(c.fingerprint));
    s << "call " << hex << " " << c.points << " " << c.first << " " << c.last << " " << c.values_per_point << " " << c.rays << "\n";
  }
  std::snprintf(hex, sizeof hex, "%016llx", static_cast<unsigned long long>(sum));
  s << "checksum " << hex << "\nend\n";
  write_file_atomically(path, s.str() + payload);
}

// The parts of `dir` that belong to the bake, by phase and shard; refuses another bake's
// parts, another shard count and two files claiming one place.
std::map<std::pair<uint32_t, uint32_t>, PartHeader> index_parts(const std::string& dir, const std::string& key, uint32_t shards) {
  std::map<std::pair<uint32_t, uint32_t>, PartHeader> at;
  for (PartHeader& h : list_parts(dir)) {
    if (h.key != key)
      throw InputError(h.path + ": a part of another bake (another input, options or prtsub); clear the folder or use another");
    if (shards && h.shards != shards)
      throw InputError(h.path + ": a part of a bake in " + std::to_string(h.shards) + " shards, not " + std::to_string(shards));
    auto [it, fresh] = at.emplace(std::make_pair(h.phase, h.shard), h);
    if (!fresh)
      throw InputError(h.path + " and " + it->second.path + " are both phase " + std::to_string(h.phase) + "'s shard " +
                       std::to_string(h.shard) + " of " + std::to_string(h.shards) + ": remove one");
  }
  return at;
}

void require_phase(const std::map<std::pair<uint32_t, uint32_t>, PartHeader>& at, const std::string& dir, uint32_t phase, uint32_t shards) {
  std::string missing;
  uint32_t n = 0, first = 0;
  for (uint32_t s = 1; s <= shards; ++s)
    if (!at.count({phase, s})) {
      if (!first) first = s;
      if (++n <= 8) missing += (missing.empty() ? "" : ", ") + std::to_string(s);
    }
  if (n)
    throw InputError(dir + ": phase " + std::to_string(phase) + " lacks " + (n == 1 ? "shard " : "shards ") + missing + (n > 8 ? ", ..." : "") +
                     " of " + std::to_string(shards) + " (" + part_name(phase, first, shards) + "): trace " + (n == 1 ? "it" : "them") + " first");
}

// One phase's calls, each gathered over every shard's slice in order.
std::vector<TraceCall> gather_phase(const std::map<std::pair<uint32_t, uint32_t>, PartHeader>& at, uint32_t phase, uint32_t shards) {
  std::vector<TraceCall> calls;
  for (uint32_t s = 1; s <= shards; ++s) {
    const std::string& path = at.at({phase, s}).path;
    std::vector<TraceCall> part = read_part_calls(path);
    if (s == 1) {
      calls.resize(part.size());
      for (size_t j = 0; j < part.size(); ++j) {
        TraceCall& c = calls[j];
        c.fingerprint = part[j].fingerprint, c.points = part[j].points, c.values_per_point = part[j].values_per_point, c.rays = part[j].rays;
        c.values.reserve(size_t(c.points) * c.values_per_point), c.variance.reserve(size_t(c.points));
      }
    }
    if (part.size() != calls.size()) throw InputError(path + ": holds " + std::to_string(part.size()) + " calls where shard 1 holds " + std::to_string(calls.size()));
    for (size_t j = 0; j < part.size(); ++j) {
      TraceCall& c = calls[j];
      const TraceCall& p = part[j];
      if (p.fingerprint != c.fingerprint || p.points != c.points || p.values_per_point != c.values_per_point || p.first != c.last)
        throw InputError(path + ": its call " + std::to_string(j + 1) + " does not continue shard " + std::to_string(s - 1) +
                         "'s (traced for another bake or another shard count)");
      c.values.insert(c.values.end(), p.values.begin(), p.values.end());
      c.variance.insert(c.variance.end(), p.variance.begin(), p.variance.end());
      c.last = p.last;
    }
  }
  for (size_t j = 0; j < calls.size(); ++j)
    if (calls[j].last != calls[j].points)
      throw InputError(at.at({phase, shards}).path + ": call " + std::to_string(j + 1) + " ends at point " + std::to_string(calls[j].last) + " of " +
                       std::to_string(calls[j].points));
  return calls;
}

}  // namespace

Part parse_part(const std::string& bytes, const std::string& path) {
  std::istringstream in(bytes);
  const ParsedHeader p = parse_header(in, path);
  Part part;
  part.calls = read_calls(in, p, bytes.size(), path);
  part.header = p.header;
  return part;
}

PartHeader read_part_header(const std::string& path) {
  std::ifstream in;
  return open_header(path, in).header;
}

std::vector<PartHeader> list_parts(const std::string& dir) {
  std::error_code ec;
  if (!fs::is_directory(dir, ec)) throw IoError(dir + ": not a folder");
  std::vector<std::string> paths;
  for (const fs::directory_entry& e : fs::directory_iterator(dir, ec))
    if (e.path().extension() == ".part" && e.is_regular_file(ec)) paths.push_back(e.path().string());
  if (ec) throw IoError(dir + ": cannot list (" + ec.message() + ")");
  std::sort(paths.begin(), paths.end());
  std::vector<PartHeader> out;
  for (const std::string& p : paths) out.push_back(read_part_header(p));
  return out;
}

ShardResult bake_shard(const Mesh& mesh, const BakeOptions& options, const ShardOptions& s, const BakeProgress& progress) {
  const Stopwatch clock;
  if (s.shards == 0 || s.shard == 0 || s.shard > s.shards) throw InputError("shard " + std::to_string(s.shard) + " of " + std::to_string(s.shards) + " does not exist");
  if (s.key.empty()) throw InputError("a sharded bake needs its content key");
  check_fixed_mesh(options);  // before the folder is made
  std::error_code ec;
  fs::create_directories(s.dir, ec);
  if (ec) throw IoError(s.dir + ": cannot create the parts folder (" + ec.message() + ")");
  const auto at = index_parts(s.dir, s.key, s.shards);
  ShardResult r;
  r.phases = shard_phases(options);
  uint32_t phase = uint32_t(std::max(0, s.phase));
  if (phase == 0) {
    phase = 1;
    while (phase <= uint32_t(r.phases) && at.count({phase, s.shard})) ++phase;
  }
  r.phase = int(phase);
  if (phase > uint32_t(r.phases)) {
    r.nothing_left = true;
    r.seconds = clock.total();
    return r;
  }
  std::vector<std::vector<TraceCall>> done;
  for (uint32_t q = 1; q < phase; ++q) {
    require_phase(at, s.dir, q, s.shards);
    done.push_back(gather_phase(at, q, s.shards));
  }
  TraceLog log(std::move(done), s.shard - 1, s.shards);
  BakeOptions o = options;
  o.transfer.log = &log;
  try {
    bake(mesh, o, progress);
    throw Error("shard: the bake ran past its last phase");
  } catch (const PhaseDone& d) {
    if (d.nothing_left) {
      r.nothing_left = true;
      r.seconds = clock.total();
      return r;
    }
  }
  PartHeader h;
  h.key = s.key, h.shard = s.shard, h.shards = s.shards, h.phase = phase, h.notes = s.notes;
  r.path = (fs::path(s.dir) / part_name(phase, s.shard, s.shards)).string();
  write_part(r.path, h, log.traced());
  r.rays = log.traced_rays();
  for (const TraceCall& c : log.traced()) r.points += c.last - c.first;
  r.bytes = size_t(fs::file_size(r.path, ec));
  r.seconds = clock.total();
  return r;
}

BakeResult bake_merged(const Mesh& mesh, const BakeOptions& options, const std::string& dir, const std::string& key, const BakeProgress& progress) {
  const auto at = index_parts(dir, key, 0);
  if (at.empty()) throw InputError(dir + ": holds no parts (*.part) to merge");
  const uint32_t shards = at.begin()->second.shards;
  for (const auto& [where, h] : at)
    if (h.shards != shards)
      throw InputError(h.path + ": a part of a bake in " + std::to_string(h.shards) + " shards, where " + at.begin()->second.path + " has " +
                       std::to_string(shards));
  const uint32_t phases = uint32_t(shard_phases(options));
  for (const auto& [where, h] : at)
    if (h.phase > phases) throw InputError(h.path + ": phase " + std::to_string(h.phase) + ", but this bake has " + std::to_string(phases));
  std::vector<std::vector<TraceCall>> all;
  for (uint32_t q = 1; q <= phases; ++q) {
    require_phase(at, dir, q, shards);
    all.push_back(gather_phase(at, q, shards));
  }
  TraceLog log(std::move(all));
  BakeOptions o = options;
  o.transfer.log = &log;
  BakeResult r = bake(mesh, o, progress);
  if (!log.past_last()) throw Error("merge: the bake did not reach its last phase");
  return r;
}

}  // namespace prtsub
