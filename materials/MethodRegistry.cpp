#include "materials/MethodRegistry.h"

#include <algorithm>
#include <cctype>
#include <filesystem>
#include <map>

#include "core/Error.h"
#include "core/ShaderSource.h"
#include "materials/MaterialSerializer.h"
#include "materials/MethodOptions.h"

namespace osgBTF {

namespace {
std::map<std::string, MethodInfo>& registry() {
    static std::map<std::string, MethodInfo> methods;
    return methods;
}

// Every registerFitter call, kept for a method registered (again) after it: a library's static
// initialisers run in an order of their own.
std::map<std::string, decltype(MethodInfo::fit)>& registeredFitters() {
    static std::map<std::string, decltype(MethodInfo::fit)> fitters;
    return fitters;
}
}  // namespace

bool registerMethod(MethodInfo info) {
    const std::string name = info.name;
    if (!info.fit) {
        if (const auto it = registeredFitters().find(name); it != registeredFitters().end())
            info.fit = it->second;
        else
            // A program that links only the render library: say what it lacks rather than let
            // std::function throw bad_function_call.
            info.fit = [name](const BtfSource&, const FitOptions&) -> osg::ref_ptr<Material> {
                throw Error("method '" + name +
                            "': fitting needs libosgBTFFit (link osgBTF::osgBTFFit or pkg-config "
                            "osgBTFFit); this program has only the render library libosgBTF");
            };
    }
    if (!info.fragmentShader.empty()) addShaderSource(name + ".frag", info.fragmentShader);
    const MethodInfo& stored = registry()[name] = std::move(info);
    addMaterialWrapper(stored);
    return true;
}

bool registerFitter(const std::string& name, decltype(MethodInfo::fit) fit) {
    if (const auto it = registry().find(name); it != registry().end()) it->second.fit = fit;
    registeredFitters()[name] = std::move(fit);
    return true;
}

std::vector<std::string> methodNames() {
    std::vector<std::string> names;
    for (const auto& entry : registry()) names.push_back(entry.first);
    return names;
}

std::vector<std::string> methodNamesInOrder() {
    std::vector<std::string> names = methodNames();
    std::stable_sort(names.begin(), names.end(), [](const std::string& a, const std::string& b) {
        return registry().at(a).order < registry().at(b).order;
    });
    return names;
}

std::vector<std::string> methodsWithOption(const std::string& option) {
    std::vector<std::string> names;
    for (const std::string& name : methodNamesInOrder())
        if (findOption(registry().at(name), option)) names.push_back(name);
    return names;
}

const MethodInfo& findMethod(const std::string& name) {
    const MethodInfo* method = findMethodIfRegistered(name);
    if (!method) {
        std::string known;
        for (const auto& n : methodNames()) known += (known.empty() ? "" : ", ") + n;
        throw Error("unknown method '" + name + "' (known: " + known + ")");
    }
    return *method;
}

const MethodInfo* findMethodIfRegistered(const std::string& name) {
    const auto it = registry().find(name);
    return it == registry().end() ? nullptr : &it->second;
}

namespace {

const MethodInfo& methodWith(bool MethodInfo::*flag, const std::string& role) {
    for (const std::string& name : methodNamesInOrder())
        if (registry().at(name).*flag) return registry().at(name);
    throw Error("no method is registered as the " + role);
}

}  // namespace

const MethodInfo& baselineMethod() {
    return methodWith(&MethodInfo::baseline, "baseline");
}

const MethodInfo& factorMethod() {
    for (const std::string& name : methodNamesInOrder())
        if (registry().at(name).factors) return registry().at(name);
    throw Error("no method is registered with UBO2014 factors (MethodInfo::factors)");
}

const MethodInfo& pluginDefaultMethod() {
    return methodWith(&MethodInfo::pluginDefault, "plugins' default");
}

std::string environmentMethodsText() {
    std::vector<std::string> names;
    for (const std::string& name : methodNamesInOrder())
        if (findMethod(name).environment) names.push_back(name);
    std::string text;
    for (std::size_t i = 0; i < names.size(); ++i)
        text += (i == 0 ? "" : i + 1 == names.size() ? " and " : ", ") + names[i];
    return text;
}

}  // namespace osgBTF
