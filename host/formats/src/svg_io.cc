// SPDX-License-Identifier: MIT
// The SVG reader's document walk (docs/formats.md, "SVG"): the page from the
// root's width, height and viewBox, groups, nested viewports and <use> with
// their transforms, what is hidden or left out (counted in a note), and the
// layers (Inkscape's, or stroke colours).
#include "fdsurf/host/svg_io.h"

#include <algorithm>
#include <functional>
#include <map>
#include <pugixml.hpp>
#include <set>
#include <utility>

#include "fdsurf/host/text.h"
#include "svg_internal.h"

namespace fdsurf::host {
namespace {

using svg::Affine;
using svg::SyntaxError;
using svg::Vec2;

// The element's name without an "svg:" prefix; "" for another namespace's
// element (inkscape:, sodipodi:), which draws nothing.
std::string LocalName(const pugi::xml_node& node) {
  std::string name = node.name();
  const std::size_t colon = name.find(':');
  if (colon == std::string::npos) return name;
  return name.substr(0, colon) == "svg" ? name.substr(colon + 1) : std::string();
}

std::string Trim(std::string_view s) {
  const auto first = s.find_first_not_of(" \t\r\n");
  if (first == std::string_view::npos) return {};
  const auto last = s.find_last_not_of(" \t\r\n");
  return std::string(s.substr(first, last - first + 1));
}

// A presentation property: style="" wins over the attribute of that name.
std::string Property(const pugi::xml_node& node, const char* name) {
  const std::string style = node.attribute("style").value();
  std::string found;
  std::size_t pos = 0;
  while (pos < style.size()) {
    std::size_t end = style.find(';', pos);
    if (end == std::string::npos) end = style.size();
    const std::string declaration = style.substr(pos, end - pos);
    const std::size_t colon = declaration.find(':');
    if (colon != std::string::npos && Trim(declaration.substr(0, colon)) == name) {
      found = Trim(declaration.substr(colon + 1));
    }
    pos = end + 1;
  }
  if (found.empty()) found = Trim(node.attribute(name).value());
  const std::size_t important = found.find("!important");
  if (important != std::string::npos) found = Trim(found.substr(0, important));
  return found;
}

// What a group passes to its children.
struct Context {
  Affine to_out;                     // user space → page, mm, y up
  std::array<double, 2> viewport{};  // width, height in user units (percentages)
  bool invisible = false;            // visibility:hidden (a child may say visible)
  std::string stroke = "none";
  int layer = -1;  // Inkscape layer, -1 outside them
  int depth = 0;
};

class Reader {
 public:
  Reader(const std::string& text, std::string name, const SvgOptions& options)
      : text_(text), name_(std::move(name)), options_(options) {
    for (std::size_t i = 0; i < text.size(); ++i) {
      if (text[i] == '\n') line_starts_.push_back(i + 1);
    }
  }

  PatchSet Read();

 private:
  FDSURF_NODISCARD int LineOf(std::ptrdiff_t offset) const {
    if (offset < 0) return 0;
    const auto it = std::upper_bound(line_starts_.begin(), line_starts_.end(),
                                     static_cast<std::size_t>(offset));
    return static_cast<int>(it - line_starts_.begin());
  }
  static std::string Describe(const pugi::xml_node& node) {
    std::string s = std::string("<") + node.name();
    const char* id = node.attribute("id").value();
    if (*id != '\0') s += std::string(" id=\"") + id + "\"";
    return s + ">";
  }
  FDSURF_NODISCARD InputError Error(const pugi::xml_node& node, const std::string& attribute,
                                    const std::string& what) const {
    return InputError(name_ + ":" + std::to_string(LineOf(node.offset_debug())) + ": " +
                      Describe(node) + (attribute.empty() ? "" : " " + attribute) + ": " + what);
  }
  FDSURF_NODISCARD double Length(const pugi::xml_node& node, const char* attribute,
                                 double fallback) const {
    const pugi::xml_attribute a = node.attribute(attribute);
    if (!a) return fallback;
    try {
      return svg::ParseLength(a.value());
    } catch (const SyntaxError& e) {
      throw Error(node, attribute, e.what());
    }
  }
  void LeftOut(const std::string& what, int count = 1) {
    for (auto& [name, n] : left_out_) {
      if (name == what) {
        n += count;
        return;
      }
    }
    left_out_.emplace_back(what, count);
  }

  void SetPage(const pugi::xml_node& root, PatchSet* set, Context* context);
  FDSURF_NODISCARD Affine ViewBox(const pugi::xml_node& node, double width, double height) const;
  void Walk(const pugi::xml_node& parent, const Context& context);
  void Element(const pugi::xml_node& node, const Context& parent);
  bool Shape(const std::string& kind, const pugi::xml_node& node, const Context& context);
  void Rect(const pugi::xml_node& node, const Context& context);
  void Oval(const std::string& kind, const pugi::xml_node& node, const Context& context);
  FDSURF_NODISCARD double NonNegative(const pugi::xml_node& node, const char* attribute) const;
  void Use(const pugi::xml_node& node, Context context);
  void Viewport(const pugi::xml_node& node, const pugi::xml_node& size_from, Context context);
  void Draw(const pugi::xml_node& node, const Context& context, const char* attribute,
            const std::function<void(svg::PathSink*)>& shape);
  void CollectIds(const pugi::xml_node& node);
  void Layers(PatchSet* set);

  const std::string& text_;
  std::string name_;
  SvgOptions options_;
  std::vector<std::size_t> line_starts_{0};
  std::map<std::string, pugi::xml_node> ids_;
  std::set<std::string> used_ids_;
  std::vector<pugi::xml_node> use_stack_;
  std::vector<std::pair<std::string, int>> left_out_;
  std::vector<std::string> inkscape_layers_;
  std::vector<Curve> curves_;
  std::vector<std::string> strokes_;  // per curve, for colour layers
};

void Reader::CollectIds(const pugi::xml_node& node) {
  for (const pugi::xml_node& child : node.children()) {
    if (child.type() != pugi::node_element) continue;
    const std::string id = child.attribute("id").value();
    if (!id.empty()) ids_.emplace(id, child);
    for (const char* href : {"href", "xlink:href"}) {
      const std::string ref = child.attribute(href).value();
      if (LocalName(child) == "use" && ref.size() > 1 && ref[0] == '#') {
        used_ids_.insert(ref.substr(1));
      }
    }
    CollectIds(child);
  }
}

// The map of a viewBox onto a viewport of width × height (user units of the
// parent, or mm for the root), per preserveAspectRatio (all nine alignments,
// meet and slice, and none).
Affine Reader::ViewBox(const pugi::xml_node& node, double width, double height) const {
  std::vector<double> box;
  try {
    box = svg::ParseNumberList(node.attribute("viewBox").value());
  } catch (const SyntaxError& e) {
    throw Error(node, "viewBox", e.what());
  }
  if (box.size() != 4) throw Error(node, "viewBox", "expected 4 numbers: min-x min-y width height");
  if (box[2] <= 0 || box[3] <= 0) throw Error(node, "viewBox", "width and height must be > 0");
  double sx = width / box[2];
  double sy = height / box[3];
  const std::string aspect = Trim(node.attribute("preserveAspectRatio").value());
  double ax = 0.5;
  double ay = 0.5;
  if (aspect != "none") {
    const bool slice = aspect.find("slice") != std::string::npos;
    const double s = slice ? std::max(sx, sy) : std::min(sx, sy);
    sx = sy = s;
    if (aspect.find("xMin") != std::string::npos) ax = 0;
    if (aspect.find("xMax") != std::string::npos) ax = 1;
    if (aspect.find("YMin") != std::string::npos) ay = 0;
    if (aspect.find("YMax") != std::string::npos) ay = 1;
  }
  return {sx,
          0,
          0,
          sy,
          ax * (width - box[2] * sx) - box[0] * sx,
          ay * (height - box[3] * sy) - box[1] * sy};
}

// The page: width and height in mm (absent or a percentage: the viewBox's
// size in px), the viewBox mapped onto it, and y flipped so the top is up.
void Reader::SetPage(const pugi::xml_node& root, PatchSet* set, Context* context) {
  const double mm_per_px = 25.4 / 96;
  auto size = [&](const char* attribute) -> double {
    const std::string value = Trim(root.attribute(attribute).value());
    if (value.empty() || value.back() == '%') return 0;
    const double px = Length(root, attribute, 0);
    if (px <= 0) throw Error(root, attribute, "must be > 0");
    return px * mm_per_px;
  };
  double width = size("width");
  double height = size("height");
  const bool has_box = root.attribute("viewBox");
  Affine user_to_mm{mm_per_px, 0, 0, mm_per_px, 0, 0};
  if (has_box) {
    std::vector<double> box;
    try {
      box = svg::ParseNumberList(root.attribute("viewBox").value());
    } catch (const SyntaxError& e) {
      throw Error(root, "viewBox", e.what());
    }
    if (box.size() == 4 && box[2] > 0 && box[3] > 0) {
      if (width == 0 && height == 0) {
        width = box[2] * mm_per_px;
        height = box[3] * mm_per_px;
      } else if (width == 0) {
        width = height * box[2] / box[3];
      } else if (height == 0) {
        height = width * box[3] / box[2];
      }
    }
    user_to_mm = ViewBox(root, width, height);
  }
  if (width > 0 && height > 0) {
    set->page = std::array<double, 2>{width, height};
    context->viewport = {width / mm_per_px, height / mm_per_px};
  } else {
    context->viewport = {300, 150};  // CSS's default replaced-element size
  }
  // y_out = page height − y (or −y without a page).
  const Affine flip{1, 0, 0, -1, 0, set->page ? height : 0};
  context->to_out = flip.After(user_to_mm);
}

PatchSet Reader::Read() {
  pugi::xml_document doc;
  const pugi::xml_parse_result parsed = doc.load_buffer(text_.data(), text_.size());
  if (!parsed) {
    throw InputError(name_ + ":" + std::to_string(LineOf(parsed.offset)) +
                     ": malformed XML: " + parsed.description());
  }
  const pugi::xml_node root = doc.document_element();
  if (LocalName(root) != "svg") {
    throw InputError(name_ + ":" + std::to_string(LineOf(root.offset_debug())) +
                     ": the root element is <" + root.name() + ">, not <svg>");
  }
  if (!(options_.arc_tolerance > 0)) {
    throw OptionError("arc tolerance", FormatNumber(options_.arc_tolerance) + " mm", "must be > 0");
  }
  CollectIds(doc);
  PatchSet set;
  set.units = "mm";
  Context context;
  SetPage(root, &set, &context);
  Walk(root, context);
  if (!left_out_.empty()) {
    std::string note = name_ + ": left out: ";
    for (std::size_t i = 0; i < left_out_.size(); ++i) {
      note += (i ? ", " : "") + std::to_string(left_out_[i].second) + " " + left_out_[i].first;
    }
    set.notes.push_back(note);
  }
  if (curves_.empty()) {
    throw InputError(name_ + ": nothing to draw: no path or shape is visible" +
                     (set.notes.empty() ? std::string() : " (" + set.notes[0] + ")"));
  }
  Layers(&set);
  set.curves = std::move(curves_);
  return set;
}

void Reader::Walk(const pugi::xml_node& parent, const Context& context) {
  for (const pugi::xml_node& child : parent.children()) {
    if (child.type() == pugi::node_element) Element(child, context);
  }
}

// One element: hidden, a container, a shape, or something left out.
void Reader::Element(const pugi::xml_node& node, const Context& parent) {
  const std::string kind = LocalName(node);
  if (kind.empty()) return;  // another namespace's element
  if (Property(node, "display") == "none") {
    LeftOut("hidden (display:none)");
    return;
  }
  Context context = parent;
  if (context.depth > 200) throw Error(node, "", "elements nested more than 200 deep");
  ++context.depth;
  const std::string visibility = Property(node, "visibility");
  if (visibility == "hidden" || visibility == "collapse") context.invisible = true;
  if (visibility == "visible") context.invisible = false;
  const std::string stroke = Property(node, "stroke");
  if (!stroke.empty() && stroke != "inherit") context.stroke = stroke;
  if (node.attribute("transform")) {
    try {
      context.to_out =
          context.to_out.After(svg::ParseTransform(node.attribute("transform").value()));
    } catch (const SyntaxError& e) {
      throw Error(node, "transform", e.what());
    }
  }
  if (kind != "svg" && kind != "use") {
    for (const char* clip : {"clip-path", "mask"}) {
      const std::string value = Property(node, clip);
      if (!value.empty() && value != "none") LeftOut(std::string(clip) + " (drawn unclipped)");
    }
  }
  if (kind == "g" || kind == "a") {
    if (parent.depth == 0 && std::string(node.attribute("inkscape:groupmode").value()) == "layer") {
      std::string label = node.attribute("inkscape:label").value();
      if (label.empty()) label = node.attribute("id").value();
      if (label.empty()) label = "layer " + std::to_string(inkscape_layers_.size() + 1);
      context.layer = static_cast<int>(inkscape_layers_.size());
      inkscape_layers_.push_back(label);
    }
    Walk(node, context);
  } else if (kind == "svg") {
    Viewport(node, node, context);
  } else if (kind == "use") {
    Use(node, context);
  } else if (kind == "defs") {
    for (const pugi::xml_node& child : node.children()) {
      if (child.type() == pugi::node_element && !LocalName(child).empty() &&
          used_ids_.count(child.attribute("id").value()) == 0) {
        LeftOut("unused <defs> element" + std::string(""));
      }
    }
  } else if (kind == "style") {
    LeftOut("<style> sheet (CSS not applied)");
  } else if (kind == "symbol") {
    if (used_ids_.count(node.attribute("id").value()) == 0) LeftOut("unused <symbol>");
  } else if (kind == "title" || kind == "desc" || kind == "metadata" || kind == "linearGradient" ||
             kind == "radialGradient" || kind == "filter" || kind == "script") {
    // No geometry: nothing is lost.
  } else if (!Shape(kind, node, context)) {
    LeftOut("<" + kind + ">");
  }
}

// A nested <svg> (or a used <symbol>): a new viewport at x, y of width ×
// height (default 100%) with its own viewBox.
void Reader::Viewport(const pugi::xml_node& node, const pugi::xml_node& size_from,
                      Context context) {
  auto percent_or = [&](const char* attribute, double whole) {
    const std::string value = Trim(size_from.attribute(attribute).value());
    if (value.empty()) return whole;
    if (value.back() == '%') {
      try {
        return whole * svg::ParseLength(value.substr(0, value.size() - 1)) / 100;
      } catch (const SyntaxError& e) {
        throw Error(size_from, attribute, e.what());
      }
    }
    return Length(size_from, attribute, whole);
  };
  // A <use> has already moved its symbol by its own x and y.
  if (node == size_from) {
    context.to_out = context.to_out.After({1, 0, 0, 1, Length(node, "x", 0), Length(node, "y", 0)});
  }
  const double width = percent_or("width", context.viewport[0]);
  const double height = percent_or("height", context.viewport[1]);
  if (node.attribute("viewBox")) {
    context.to_out = context.to_out.After(ViewBox(node, width, height));
    const std::vector<double> box = svg::ParseNumberList(node.attribute("viewBox").value());
    context.viewport = {box[2], box[3]};
  } else {
    context.viewport = {width, height};
  }
  if (LocalName(node) != "svg" && LocalName(node) != "symbol") return;
  Walk(node, context);
}

// <use href="#id" x y>: the element drawn again, translated by (x, y), with
// the <use>'s own properties inherited.
void Reader::Use(const pugi::xml_node& node, Context context) {
  std::string ref = node.attribute("href").value();
  const char* attribute = "href";
  if (ref.empty()) {
    ref = node.attribute("xlink:href").value();
    attribute = "xlink:href";
  }
  if (ref.size() < 2 || ref[0] != '#') {
    throw Error(node, attribute, "expected a reference to an element of this file, like #id");
  }
  const auto it = ids_.find(ref.substr(1));
  if (it == ids_.end())
    throw Error(node, attribute, "no element has the id '" + ref.substr(1) + "'");
  const pugi::xml_node target = it->second;
  if (std::find(use_stack_.begin(), use_stack_.end(), target) != use_stack_.end()) {
    throw Error(node, attribute, "refers to an element that contains this <use> (a cycle)");
  }
  context.to_out = context.to_out.After({1, 0, 0, 1, Length(node, "x", 0), Length(node, "y", 0)});
  use_stack_.push_back(target);
  if (LocalName(target) == "symbol") {
    // Its own properties, then its viewport sized by the <use>.
    Context inner = context;
    const std::string stroke = Property(target, "stroke");
    if (!stroke.empty()) inner.stroke = stroke;
    Viewport(target, node, inner);
  } else {
    Element(target, context);
  }
  use_stack_.pop_back();
}

void Reader::Draw(const pugi::xml_node& node, const Context& context, const char* attribute,
                  const std::function<void(svg::PathSink*)>& shape) {
  if (context.invisible) {
    LeftOut("hidden (visibility:hidden)");
    return;
  }
  std::vector<Curve> curves;
  svg::CurveSink sink(
      context.to_out, options_.arc_tolerance,
      name_ + ": " + Describe(node) + " (line " + std::to_string(LineOf(node.offset_debug())) + ")",
      &curves);
  try {
    shape(&sink);
  } catch (const SyntaxError& e) {
    throw Error(node, attribute, e.what());
  } catch (const ConstructionError& e) {
    throw Error(node, attribute, e.what());
  }
  for (Curve& curve : curves) {
    curve.layer = context.layer;
    curves_.push_back(std::move(curve));
    strokes_.push_back(context.stroke);
  }
  for (const char* marker : {"marker-start", "marker-mid", "marker-end", "marker"}) {
    const std::string value = Property(node, marker);
    if (!value.empty() && value != "none") {
      LeftOut("marker (not drawn)");
      break;
    }
  }
}

// The basic shapes as path segments (SVG 2 §10: rect with rx/ry, their
// auto rule and clamping; circle; ellipse; line; polyline; polygon) and
// <path>. False for an element that is none of them.
bool Reader::Shape(const std::string& kind, const pugi::xml_node& node, const Context& context) {
  if (kind == "path") {
    const std::string d = node.attribute("d").value();
    Draw(node, context, "d", [&](svg::PathSink* sink) { svg::ParsePathData(d, sink); });
  } else if (kind == "line") {
    const Vec2 a{Length(node, "x1", 0), Length(node, "y1", 0)};
    const Vec2 b{Length(node, "x2", 0), Length(node, "y2", 0)};
    Draw(node, context, "", [&](svg::PathSink* sink) { sink->Line(a, b); });
  } else if (kind == "polyline" || kind == "polygon") {
    std::vector<double> v;
    try {
      v = svg::ParseNumberList(node.attribute("points").value());
    } catch (const SyntaxError& e) {
      throw Error(node, "points", e.what());
    }
    if (v.size() % 2 != 0) throw Error(node, "points", "an odd number of coordinates");
    Draw(node, context, "points", [&](svg::PathSink* sink) {
      for (std::size_t i = 2; i + 1 < v.size(); i += 2) {
        sink->Line({v[i - 2], v[i - 1]}, {v[i], v[i + 1]});
      }
      if (kind == "polygon" && v.size() >= 4 && (v[0] != v[v.size() - 2] || v[1] != v.back())) {
        sink->Line({v[v.size() - 2], v.back()}, {v[0], v[1]});
      }
    });
  } else if (kind == "rect") {
    Rect(node, context);
  } else if (kind == "circle" || kind == "ellipse") {
    Oval(kind, node, context);
  } else {
    return false;
  }
  return true;
}

double Reader::NonNegative(const pugi::xml_node& node, const char* attribute) const {
  const double v = Length(node, attribute, 0);
  if (v < 0) throw Error(node, attribute, "must not be negative");
  return v;
}

// <rect>: four edges, and with rx, ry four quarter arcs clockwise on the
// screen from the top edge (SVG 2's order).
void Reader::Rect(const pugi::xml_node& node, const Context& context) {
  const double x = Length(node, "x", 0);
  const double y = Length(node, "y", 0);
  const double w = NonNegative(node, "width");
  const double h = NonNegative(node, "height");
  const bool auto_rx = !node.attribute("rx") || Trim(node.attribute("rx").value()) == "auto";
  const bool auto_ry = !node.attribute("ry") || Trim(node.attribute("ry").value()) == "auto";
  double rx = auto_rx ? 0 : NonNegative(node, "rx");
  double ry = auto_ry ? 0 : NonNegative(node, "ry");
  if (auto_rx) rx = ry;
  if (auto_ry) ry = rx;
  rx = std::min(rx, w / 2);
  ry = std::min(ry, h / 2);
  if (w == 0 || h == 0) return;  // SVG 2: not rendered
  Draw(node, context, "", [&](svg::PathSink* sink) {
    const bool round = rx > 0 && ry > 0;
    const Vec2 corners[4][2] = {{{x + w - rx, y}, {x + w, y + ry}},
                                {{x + w, y + h - ry}, {x + w - rx, y + h}},
                                {{x + rx, y + h}, {x, y + h - ry}},
                                {{x, y + ry}, {x + rx, y}}};
    for (int i = 0; i < 4; ++i) {
      const Vec2& edge_start = corners[(i + 3) % 4][1];
      if (round) {
        if (edge_start != corners[i][0]) sink->Line(edge_start, corners[i][0]);
        sink->Arc(corners[i][0], rx, ry, 0, false, true, corners[i][1]);
      } else {
        sink->Line(corners[(i + 3) % 4][0], corners[i][0]);
      }
    }
  });
}

// <circle>, <ellipse>: four quarter arcs.
void Reader::Oval(const std::string& kind, const pugi::xml_node& node, const Context& context) {
  const double cx = Length(node, "cx", 0);
  const double cy = Length(node, "cy", 0);
  double rx = 0;
  double ry = 0;
  if (kind == "circle") {
    rx = ry = NonNegative(node, "r");
  } else {
    const bool auto_rx = !node.attribute("rx") || Trim(node.attribute("rx").value()) == "auto";
    const bool auto_ry = !node.attribute("ry") || Trim(node.attribute("ry").value()) == "auto";
    rx = auto_rx ? 0 : NonNegative(node, "rx");
    ry = auto_ry ? 0 : NonNegative(node, "ry");
    if (auto_rx) rx = ry;
    if (auto_ry) ry = rx;
  }
  if (rx == 0 || ry == 0) return;  // SVG 2: not rendered
  Draw(node, context, "", [&](svg::PathSink* sink) {
    // Four quarters from the rightmost point, in the positive angle
    // direction (clockwise on screen, as SVG 2 draws them).
    const Vec2 points[5] = {
        {cx + rx, cy}, {cx, cy + ry}, {cx - rx, cy}, {cx, cy - ry}, {cx + rx, cy}};
    for (int i = 0; i < 4; ++i) sink->Arc(points[i], rx, ry, 0, false, true, points[i + 1]);
  });
}

// Inkscape layers when there are any (curves outside them get a layer of
// their own), else one layer per stroke colour when there are several.
void Reader::Layers(PatchSet* set) {
  std::vector<int> order;  // layer index → position in set->layers
  if (!inkscape_layers_.empty()) {
    std::map<int, int> position;
    for (Curve& curve : curves_) {
      const auto [it, added] = position.emplace(curve.layer, static_cast<int>(set->layers.size()));
      if (added) {
        set->layers.push_back(curve.layer < 0 ? std::string("(outside layers)")
                                              : inkscape_layers_[curve.layer]);
      }
      curve.layer = it->second;
    }
    return;
  }
  std::vector<std::string> colours;
  for (std::size_t i = 0; i < curves_.size(); ++i) {
    const auto it = std::find(colours.begin(), colours.end(), strokes_[i]);
    curves_[i].layer = static_cast<int>(it - colours.begin());
    if (it == colours.end()) colours.push_back(strokes_[i]);
  }
  if (colours.size() > 1) {
    set->layers = colours;
  } else {
    for (Curve& curve : curves_) curve.layer = 0;
  }
}

}  // namespace

PatchSet ReadSvg(const std::string& text, const std::string& name, const SvgOptions& options) {
  return Reader(text, name, options).Read();
}

bool LooksLikeSvg(std::string_view text) {
  std::size_t first = 0;
  if (text.substr(0, 3) == "\xEF\xBB\xBF") first = 3;  // a UTF-8 byte order mark
  first = text.find_first_not_of(" \t\r\n", first);
  if (first == std::string_view::npos) return false;
  const std::string_view start = text.substr(first);
  if (start.substr(0, 4) == "<svg") return true;
  if (start.substr(0, 5) == "<?xml" || start.substr(0, 4) == "<!--" ||
      start.substr(0, 9) == "<!DOCTYPE") {
    return text.substr(0, 4096).find("<svg") != std::string_view::npos;
  }
  return false;
}

void SelectLayer(PatchSet* set, const std::string& spec) {
  auto available = [&] {
    std::string list;
    for (std::size_t i = 0; i < set->layers.size(); ++i) {
      list += (i ? ", " : "") + std::to_string(i + 1) + " \"" + set->layers[i] + "\"";
    }
    return list;
  };
  if (set->layers.empty()) {
    throw InputError("--layer " + spec + ": the drawing has no layers");
  }
  int chosen = -1;
  for (std::size_t i = 0; i < set->layers.size(); ++i) {
    if (set->layers[i] == spec) chosen = static_cast<int>(i);
  }
  if (chosen < 0 && !spec.empty() && spec.find_first_not_of("0123456789") == std::string::npos &&
      spec.size() < 6) {
    const int number = std::stoi(spec);
    if (number >= 1 && number <= static_cast<int>(set->layers.size())) chosen = number - 1;
  }
  if (chosen < 0) {
    throw InputError("--layer " + spec + ": no such layer; the drawing has " + available());
  }
  std::vector<Curve> kept;
  for (Curve& curve : set->curves) {
    if (curve.layer == chosen) {
      curve.layer = 0;
      kept.push_back(std::move(curve));
    }
  }
  set->curves = std::move(kept);
  set->layers = {set->layers[static_cast<std::size_t>(chosen)]};
}

}  // namespace fdsurf::host
