#include "materials/MethodOptions.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <sstream>
#include <stdexcept>

#include "core/Error.h"
#include "materials/MethodRegistry.h"

namespace osgBTF {

FitOptions FitOptions::parse(const std::string& text) {
    std::string normalised = text;
    std::replace(normalised.begin(), normalised.end(), ',', ' ');
    std::istringstream in(normalised);
    std::string item;
    FitOptions options;
    while (in >> item) {
        const auto eq = item.find('=');
        if (eq == std::string::npos || eq == 0)
            throw Error("option '" + item + "': expected KEY=VALUE");
        options.set(item.substr(0, eq), item.substr(eq + 1));
    }
    return options;
}

namespace {

std::string numberText(double value) {
    char text[32];
    std::snprintf(text, sizeof text, "%g", value);
    return text;
}

std::string joined(const std::vector<std::string>& items) {
    std::string text;
    for (const std::string& item : items) text += (text.empty() ? "" : ", ") + item;
    return text;
}

bool parseInt(const std::string& text, int& value) {
    try {
        std::size_t used = 0;
        value = std::stoi(text, &used);
        return used == text.size();
    } catch (const std::exception&) {
        return false;
    }
}

bool parseNumber(const std::string& text, double& value) {
    try {
        std::size_t used = 0;
        value = std::stod(text, &used);
        return used == text.size();
    } catch (const std::exception&) {
        return false;
    }
}

}  // namespace

// ---- OptionSpec ------------------------------------------------------------------------------

OptionSpec OptionSpec::integer(std::string name, int defaultValue, int min, int max,
                               std::string doc) {
    OptionSpec o;
    o.name = std::move(name);
    o.type = Type::Int;
    o.defaultValue = std::to_string(defaultValue);
    o.min = min;
    o.max = max;
    o.doc = std::move(doc);
    return o;
}

OptionSpec OptionSpec::number(std::string name, double defaultValue, double min, double max,
                              std::string doc) {
    OptionSpec o;
    o.name = std::move(name);
    o.type = Type::Float;
    o.defaultValue = numberText(defaultValue);
    o.min = min;
    o.max = max;
    o.doc = std::move(doc);
    return o;
}

OptionSpec OptionSpec::choice(std::string name, std::string defaultValue,
                              std::vector<std::string> choices, std::string doc) {
    OptionSpec o;
    o.name = std::move(name);
    o.type = Type::Enum;
    o.defaultValue = std::move(defaultValue);
    o.choices = std::move(choices);
    o.doc = std::move(doc);
    return o;
}

OptionSpec OptionSpec::flag(std::string name, bool defaultValue, std::string doc) {
    OptionSpec o;
    o.name = std::move(name);
    o.type = Type::Bool;
    o.defaultValue = defaultValue ? "1" : "0";
    o.min = 0;
    o.max = 1;
    o.doc = std::move(doc);
    return o;
}

OptionSpec OptionSpec::multipleOf(int multiple) const {
    if (type != Type::Int || multiple < 1)
        throw std::logic_error(name + ": only an integer option has a step, and it is >= 1");
    OptionSpec o = *this;
    o.step = multiple;
    return o;
}

std::string OptionSpec::allowed() const {
    switch (type) {
        case Type::Int: {
            const std::string what =
                step > 1 ? "a multiple of " + std::to_string(step) : std::string("an integer");
            if (max == kNoLimit) return what + " >= " + numberText(min);
            return what + " in " + numberText(min) + ".." + numberText(max);
        }
        case Type::Float:
            return "a number in " + numberText(min) + ".." + numberText(max);
        case Type::Enum:
            return "one of " + joined(choices);
        case Type::Bool:
            return "0 or 1";
    }
    return {};
}

std::string OptionSpec::typeName() const {
    switch (type) {
        case Type::Int:
            return "integer";
        case Type::Float:
            return "number";
        case Type::Enum:
            return "enum";
        case Type::Bool:
            return "bool";
    }
    return {};
}

// ---- OptionValues ----------------------------------------------------------------------------

const OptionValues::Value& OptionValues::get(const std::string& name, OptionSpec::Type type) const {
    const auto it = _values.find(name);
    if (it == _values.end())
        throw std::logic_error(_method + ": option " + name + " is not in the option table");
    if (it->second.type != type)
        throw std::logic_error(_method + ": option " + name + " read with the wrong type");
    return it->second;
}

int OptionValues::integer(const std::string& name) const {
    return int(get(name, OptionSpec::Type::Int).number);
}

double OptionValues::number(const std::string& name) const {
    return get(name, OptionSpec::Type::Float).number;
}

bool OptionValues::flag(const std::string& name) const {
    return get(name, OptionSpec::Type::Bool).number != 0;
}

const std::string& OptionValues::choice(const std::string& name) const {
    return get(name, OptionSpec::Type::Enum).text;
}

bool OptionValues::given(const std::string& name) const {
    const auto it = _values.find(name);
    return it != _values.end() && it->second.given;
}

// ---- validation ------------------------------------------------------------------------------

const OptionSpec* findOption(const MethodInfo& method, const std::string& name) {
    for (const OptionSpec& option : method.options)
        if (option.name == name) return &option;
    return nullptr;
}

OptionValues validateOptions(const MethodInfo& method, const FitOptions& options) {
    for (const auto& entry : options.values())
        if (!findOption(method, entry.first)) {
            std::vector<std::string> names;
            for (const OptionSpec& option : method.options) names.push_back(option.name);
            throw Error(method.name + ": option " + entry.first +
                        " is unknown (known: " + (names.empty() ? "none" : joined(names)) + ")");
        }
    OptionValues result;
    result._method = method.name;
    for (const OptionSpec& option : method.options) {
        OptionValues::Value value;
        value.type = option.type;
        value.given = options.has(option.name);
        value.text = value.given ? options.values().at(option.name) : option.defaultValue;
        bool ok = false;
        switch (option.type) {
            case OptionSpec::Type::Int:
            case OptionSpec::Type::Bool: {
                int parsed = 0;
                ok = parseInt(value.text, parsed) && parsed >= option.min && parsed <= option.max &&
                     parsed % option.step == 0;
                value.number = parsed;
                break;
            }
            case OptionSpec::Type::Float:
                // NaN fails both comparisons.
                ok = parseNumber(value.text, value.number) && value.number >= option.min &&
                     value.number <= option.max;
                break;
            case OptionSpec::Type::Enum:
                for (const std::string& c : option.choices) ok |= c == value.text;
                break;
        }
        if (!ok)
            throw Error(method.name + ": option " + option.name + " must be " + option.allowed() +
                        ", got " + value.text);
        result._values[option.name] = value;
    }
    return result;
}

OptionValues validateOptions(const std::string& method, const FitOptions& options) {
    return validateOptions(findMethod(method), options);
}

// ---- documentation ---------------------------------------------------------------------------

std::string optionHelp(const OptionSpec& option) {
    std::string allowed = option.allowed();
    // "an integer in 1..8" reads "integer in 1..8" inside brackets.
    if (allowed.rfind("an ", 0) == 0)
        allowed = allowed.substr(3);
    else if (allowed.rfind("a ", 0) == 0)
        allowed = allowed.substr(2);
    return option.doc + " (" + allowed + ", default " + option.defaultValue + ")";
}

std::string methodsHelp() {
    std::string text = "Compression method:";
    for (const std::string& name : methodNames()) {
        const MethodInfo& info = findMethod(name);
        text += "\n  " + name + ": " + info.description;
        if (info.options.empty()) text += "\n      (no options)";
        for (const OptionSpec& option : info.options)
            text += "\n      " + option.name + "=  " + optionHelp(option);
    }
    return text;
}

std::string optionTableMarkdown(const MethodInfo& method) {
    if (method.options.empty()) return "No options: any option given is an error.\n";
    std::string text = "| option | type | default | allowed | meaning |\n|---|---|---|---|---|\n";
    for (const OptionSpec& o : method.options)
        text += "| `" + o.name + "` | " + o.typeName() + " | `" + o.defaultValue + "` | " +
                o.allowed() + " | " + o.doc + " |\n";
    return text;
}

}  // namespace osgBTF
