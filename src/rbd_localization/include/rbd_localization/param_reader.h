// Typed reading of a node's private namespace as the parameter server delivers it (an XmlRpc
// struct), with clear errors, YAML 1.1's typing quirks accepted as robot_localization accepts them,
// and a record of which keys were read (so unknown keys can be reported). No master needed.
#ifndef RBD_LOCALIZATION_PARAM_READER_H
#define RBD_LOCALIZATION_PARAM_READER_H

#include <XmlRpcValue.h>

#include <map>
#include <set>
#include <string>
#include <vector>

namespace rbd_localization {

/// A short description of a parameter value for error messages ("the string 'abc'", "a list of 3").
std::string describeValue(const XmlRpc::XmlRpcValue& value);

/// A number written as text, read as r_l reads matrix entries (a C-locale stream), but the
/// whole text must be the number (r_l silently keeps the leading number or 0).
bool parseNumberText(const std::string& text, double* out);

/// A number as text for messages: C locale, 17 significant digits (round trip).
std::string formatNumber(double v);

/// Reads typed values out of a private namespace and remembers which keys were read. Every
/// reader returns true when the key is absent (leaving *out untouched) or its value was read,
/// false after setting the error (fail()) when the value cannot be used.
class ParamReader {
 public:
  /// `peer`: the reader the messages compare with (what it would do with a text number or a
  /// non-boolean); empty: no comparison in the messages.
  ParamReader(const XmlRpc::XmlRpcValue& ns, std::vector<std::string>* warnings, std::string* error,
              const std::string& peer = "robot_localization");

  bool has(const std::string& key) const { return values_.count(key) > 0; }
  /// The value of key (marked as read), or nullptr when it is not set.
  const XmlRpc::XmlRpcValue* take(const std::string& key);
  /// Sets the error; returns false.
  bool fail(const std::string& message);
  void warn(const std::string& message) { warnings_->push_back(message); }

  /// A scalar number. Text holding a number is read (YAML 1.1 makes `1e-2` text), with a
  /// warning: r_l's nh.param() ignores text and keeps its default.
  bool number(const std::string& key, double* out);
  /// A whole number (a double is rounded as roscpp does; text as for number()).
  bool integer(const std::string& key, int* out);
  bool boolean(const std::string& key, bool* out);
  bool text(const std::string& key, std::string* out);
  /// A list of numbers as r_l reads its matrices: every entry through a string stream, so ints,
  /// doubles and text such as `1e-9` (YAML 1.1 text) are all numbers; booleans read as 1 and 0.
  /// *present tells whether the key was set.
  bool numberList(const std::string& key, std::vector<double>* out, bool* present);

  /// Keys present but never read.
  std::vector<std::string> unread() const;

 private:
  std::map<std::string, XmlRpc::XmlRpcValue> values_;
  std::set<std::string> read_;
  std::vector<std::string>* warnings_;
  std::string* error_;
  std::string peer_;
};

}  // namespace rbd_localization

#endif  // RBD_LOCALIZATION_PARAM_READER_H
