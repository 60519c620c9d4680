#include "server/tls_roles.hpp"
#include "codec/function_set.hpp"

namespace mbstorm::server {

Error TlsRoles::add_rule(std::string_view text) {
    const std::size_t eq = text.find('=');
    if (eq == std::string_view::npos || eq == 0 || eq + 1 == text.size())
        return Error(ErrorCode::InvalidInput,
                     "a role rule is ROLE=FC,FC-FC,... (for example Operator=1-6,15,16)");
    FunctionSet set;
    if (std::string why = codec::parse_function_set(text.substr(eq + 1), set); !why.empty())
        return Error(ErrorCode::InvalidInput, "role rule '" + std::string(text) + "': " + why);
    allow(std::string(text.substr(0, eq)), set);
    return Error::none();
}

void TlsRoles::allow(std::string role, const FunctionSet& functions) {
    for (auto& [name, set] : roles_) {
        if (name == role) {
            set |= functions;
            return;
        }
    }
    roles_.emplace_back(std::move(role), functions);
}

const FunctionSet* TlsRoles::allowed_for(std::string_view role) const noexcept {
    if (roles_.empty()) return nullptr;
    static const FunctionSet kNothing;
    for (const auto& [name, set] : roles_)
        if (name == role) return &set;
    return &kNothing;
}

}  // namespace mbstorm::server
