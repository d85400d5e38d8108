#include "rbd_localization/param_reader.h"

#include <cmath>
#include <locale>
#include <sstream>

namespace rbd_localization {

using XmlRpc::XmlRpcValue;

std::string describeValue(const XmlRpcValue& value) {
  XmlRpcValue v = value;  // the conversion operators are non-const
  std::ostringstream os;
  switch (v.getType()) {
    case XmlRpcValue::TypeBoolean:
      os << "the boolean " << (static_cast<bool&>(v) ? "true" : "false");
      break;
    case XmlRpcValue::TypeInt:
      os << "the integer " << static_cast<int&>(v);
      break;
    case XmlRpcValue::TypeDouble:
      os << "the number " << static_cast<double&>(v);
      break;
    case XmlRpcValue::TypeString:
      os << "the string '" << static_cast<std::string&>(v) << "'";
      break;
    case XmlRpcValue::TypeArray:
      os << "a list of " << v.size();
      break;
    case XmlRpcValue::TypeStruct:
      os << "a dictionary";
      break;
    default:
      os << "a value of XmlRpc type " << static_cast<int>(v.getType());
  }
  return os.str();
}

bool parseNumberText(const std::string& text, double* out) {
  std::istringstream is(text);
  is.imbue(std::locale::classic());
  double v = 0.0;
  is >> v;
  if (is.fail()) return false;
  is >> std::ws;
  if (!is.eof()) return false;
  *out = v;
  return true;
}

std::string formatNumber(double v) {
  if (std::isnan(v)) return "NaN";
  if (std::isinf(v)) return v > 0 ? "Infinity" : "-Infinity";
  std::ostringstream os;
  os.imbue(std::locale::classic());
  os.precision(17);
  os << v;
  return os.str();
}

ParamReader::ParamReader(const XmlRpcValue& ns, std::vector<std::string>* warnings, std::string* error,
                         const std::string& peer)
    : warnings_(warnings), error_(error), peer_(peer) {
  XmlRpcValue copy = ns;  // begin()/end() are non-const in older xmlrpcpp (Melodic)
  if (copy.getType() == XmlRpcValue::TypeStruct) {
    for (auto it = copy.begin(); it != copy.end(); ++it) values_[it->first] = it->second;
  }
}

const XmlRpcValue* ParamReader::take(const std::string& key) {
  auto it = values_.find(key);
  if (it == values_.end()) return nullptr;
  read_.insert(key);
  return &it->second;
}

bool ParamReader::fail(const std::string& message) {
  *error_ = message;
  return false;
}

bool ParamReader::number(const std::string& key, double* out) {
  const XmlRpcValue* v = take(key);
  if (!v) return true;
  XmlRpcValue c = *v;
  switch (c.getType()) {
    case XmlRpcValue::TypeInt:
      *out = static_cast<int&>(c);
      return true;
    case XmlRpcValue::TypeDouble:
      *out = static_cast<double&>(c);
      return true;
    case XmlRpcValue::TypeString: {
      double d = 0.0;
      if (parseNumberText(static_cast<std::string&>(c), &d)) {
        warn(key + " is " + describeValue(c) +
             " (YAML 1.1 reads a number such as 1e-2, without '.' and sign in " +
             "the exponent, as text); read as " + formatNumber(d) + ". " +
             (peer_.empty() ? std::string("Write it as 1.0e-2 to have it read as a number.")
                            : peer_ + " would ignore it and use its default; write it as 1.0e-2 to be read "
                                      "alike by both."));
        *out = d;
        return true;
      }
      break;
    }
    default:
      break;
  }
  return fail(key + " must be a number, got " + describeValue(c));
}

bool ParamReader::integer(const std::string& key, int* out) {
  if (!has(key)) return true;
  double d = *out;
  if (!number(key, &d)) return false;
  if (!std::isfinite(d) || std::fabs(d) > 1e9) return fail(key + " must be a whole number");
  const double rounded = std::floor(d + 0.5);
  if (rounded != d)
    warn(key + " = " + formatNumber(d) + " is not a whole number; rounded to " + formatNumber(rounded));
  *out = static_cast<int>(rounded);
  return true;
}

bool ParamReader::boolean(const std::string& key, bool* out) {
  const XmlRpcValue* v = take(key);
  if (!v) return true;
  XmlRpcValue c = *v;
  if (c.getType() != XmlRpcValue::TypeBoolean) {
    return fail(key + " must be true or false, got " + describeValue(c) +
                (peer_.empty() ? std::string() : " (" + peer_ + " would silently use its default)"));
  }
  *out = static_cast<bool&>(c);
  return true;
}

bool ParamReader::text(const std::string& key, std::string* out) {
  const XmlRpcValue* v = take(key);
  if (!v) return true;
  XmlRpcValue c = *v;
  if (c.getType() != XmlRpcValue::TypeString) return fail(key + " must be a string, got " + describeValue(c));
  *out = static_cast<std::string&>(c);
  return true;
}

bool ParamReader::numberList(const std::string& key, std::vector<double>* out, bool* present) {
  const XmlRpcValue* v = take(key);
  *present = v != nullptr;
  if (!v) return true;
  XmlRpcValue c = *v;
  if (c.getType() != XmlRpcValue::TypeArray)
    return fail(key + " must be a list of numbers, got " + describeValue(c));
  out->clear();
  bool warned_bool = false;
  for (int i = 0; i < c.size(); ++i) {
    XmlRpcValue e = c[i];
    const std::string where = key + "[" + std::to_string(i) + "]";
    switch (e.getType()) {
      case XmlRpcValue::TypeInt:
        out->push_back(static_cast<int&>(e));
        break;
      case XmlRpcValue::TypeDouble:
        out->push_back(static_cast<double&>(e));
        break;
      case XmlRpcValue::TypeBoolean:
        if (!warned_bool) {
          warn(where + " is a boolean; read as " + (static_cast<bool&>(e) ? "1" : "0") +
               " (and so are the list's other booleans), as robot_localization does");
          warned_bool = true;
        }
        out->push_back(static_cast<bool&>(e) ? 1.0 : 0.0);
        break;
      case XmlRpcValue::TypeString: {
        double d = 0.0;
        if (!parseNumberText(static_cast<std::string&>(e), &d)) {
          return fail(where + " is " + describeValue(e) + ", not a number");
        }
        out->push_back(d);
        break;
      }
      default:
        return fail(where + " is " + describeValue(e) + ", not a number");
    }
  }
  return true;
}

std::vector<std::string> ParamReader::unread() const {
  std::vector<std::string> out;
  for (const auto& kv : values_) {
    if (!read_.count(kv.first)) out.push_back(kv.first);
  }
  return out;
}

}  // namespace rbd_localization
