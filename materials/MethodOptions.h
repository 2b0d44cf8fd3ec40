// osgBTF: a method's fit options, declared once (name, type, default, range, one line of doc).
//
// Every option map that reaches a method (btf fit --set, btf compare --set, the plugin's -O
// string, FitOptions in code) is checked against the method's table by validateOptions(), which
// is the only place that reports option errors, always as
//   "<method>: option <name> must be <what the table allows>, got <the text given>"
//   "<method>: option <name> is unknown (known: <names>)".
// The fitter then reads typed values that are known to be valid, defaults included. The same
// tables produce `btf fit --help`, the plugin's option documentation and the README tables.
#pragma once

#include <limits>
#include <map>
#include <string>
#include <utility>
#include <vector>

namespace osgBTF {

struct MethodInfo;

/** Method settings from the command line or a plugin option string: "lobes=2 clusters=32". */
class FitOptions {
public:
    FitOptions() = default;
    explicit FitOptions(std::map<std::string, std::string> values) : _values(std::move(values)) {}
    /** Parses "key=value key=value" (spaces or commas between pairs). Throws Error. */
    static FitOptions parse(const std::string& text);

    void set(const std::string& key, const std::string& value) { _values[key] = value; }
    bool has(const std::string& key) const { return _values.count(key) != 0; }
    /** The pairs as given, values as text: validateOptions (below) checks them against
     *  a method's option table and gives typed values. */
    const std::map<std::string, std::string>& values() const { return _values; }

private:
    std::map<std::string, std::string> _values;
};

/** One fit option of a method. Build with the static helpers: OptionSpec::integer("lobes", 2, 1,
 *  8, "number of lobes"). */
struct OptionSpec {
    enum class Type { Int, Float, Enum, Bool };

    std::string name;
    Type type = Type::Int;
    std::string defaultValue;          ///< as text, as a user would type it
    double min = 0, max = 0;           ///< Int and Float: inclusive range
    int step = 1;                      ///< Int: the value is a multiple of it (multipleOf)
    std::vector<std::string> choices;  ///< Enum: allowed values
    std::string doc;                   ///< one line, without default or range

    static constexpr int kNoLimit = std::numeric_limits<int>::max();

    /** An integer in [min, max]; max = kNoLimit for no upper bound. */
    static OptionSpec integer(std::string name, int defaultValue, int min, int max,
                              std::string doc);
    /** A real number in [min, max] (NaN is out of range). */
    static OptionSpec number(std::string name, double defaultValue, double min, double max,
                             std::string doc);
    /** One of `choices`. */
    static OptionSpec choice(std::string name, std::string defaultValue,
                             std::vector<std::string> choices, std::string doc);
    /** 0 or 1. */
    static OptionSpec flag(std::string name, bool defaultValue, std::string doc);
    /** This integer option, allowing only multiples of `step`:
     *  OptionSpec::integer("units", 32, 4, 64, "units").multipleOf(4). */
    OptionSpec multipleOf(int step) const;

    /** What the value must be, as the error message and the help say it: "an integer in 1..8",
     *  "an integer >= 1", "a multiple of 4 in 4..32", "a number in 1..256", "one of unorm8, half,
     *  float", "0 or 1". */
    std::string allowed() const;
    /** "integer", "number", "enum", "bool". */
    std::string typeName() const;
};

/** A method's options after validateOptions(): every declared option with its value (the given
 *  one or the default), typed. Asking for an undeclared option or with the wrong type is a
 *  programming error (std::logic_error). */
class OptionValues {
public:
    int integer(const std::string& name) const;
    double number(const std::string& name) const;
    bool flag(const std::string& name) const;
    const std::string& choice(const std::string& name) const;
    /** Whether the option was given (false: its value is the default). */
    bool given(const std::string& name) const;
    const std::string& method() const { return _method; }

private:
    friend OptionValues validateOptions(const MethodInfo& method, const FitOptions& options);
    struct Value {
        OptionSpec::Type type;
        std::string text;
        double number = 0;
        bool given = false;
    };
    const Value& get(const std::string& name, OptionSpec::Type type) const;
    std::string _method;
    std::map<std::string, Value> _values;
};

/** Checks `options` against the method's option table and returns the typed values. Throws
 *  Error "<method>: option <name> must be ..., got ..." or "<method>: option <name> is unknown
 *  (known: ...)" (names in table order; "none" for a method without options). */
OptionValues validateOptions(const MethodInfo& method, const FitOptions& options);
/** The same, by registered method name (throws Error for an unknown method). */
OptionValues validateOptions(const std::string& method, const FitOptions& options);

/** The option of `method` called `name`, or nullptr. */
const OptionSpec* findOption(const MethodInfo& method, const std::string& name);

/** "number of lobes (integer in 1..8, default 2)": the doc with what the table allows. */
std::string optionHelp(const OptionSpec& option);

/** `btf fit --help`'s method list: every registered method, its description and its options. */
std::string methodsHelp();

/** The Markdown option table of a method's README (materials/<method>/README.md, "## Options"):
 *  header "| option | type | default | allowed | meaning |" and one row per option, or one line
 *  saying there are none. */
std::string optionTableMarkdown(const MethodInfo& method);

}  // namespace osgBTF
