"""A stand-in for the Unreal Editor's `unreal` module with just the calls hairfit's export script
makes (names and signatures as the UE 5.x Python API documents them), recording what the script
does so tests/files/export_unreal.rs can check it without the editor. The state is written as JSON to
the file named by HAIRFIT_UNREAL_STUB_OUT when the script saves the instance; the parent
materials and their parameters come from HAIRFIT_UNREAL_STUB_PARENTS (JSON: path -> [scalar
names, vector names])."""

import json
import os

_assets = {}
_saved = []


class Name(str):
    pass


class LinearColor:
    def __init__(self, r, g, b, a):
        self.r, self.g, self.b, self.a = r, g, b, a


class MaterialInstanceConstant:
    pass


class MaterialInstanceConstantFactoryNew:
    pass


class _Material:
    def __init__(self, path, scalars, vectors):
        self.path, self.scalars, self.vectors = path, scalars, vectors


class _Instance:
    def __init__(self, path):
        self.path = path
        self.parent = None
        self.scalars = {}
        self.vectors = {}
        self.updated = False

    def get_path_name(self):
        return self.path


for _path, (_scalars, _vectors) in json.loads(os.environ["HAIRFIT_UNREAL_STUB_PARENTS"]).items():
    _assets[_path] = _Material(_path, _scalars, _vectors)


def _dump():
    instances = [a for a in _assets.values() if isinstance(a, _Instance)]
    state = [
        {
            "path": i.path,
            "parent": i.parent.path if i.parent else None,
            "scalars": i.scalars,
            "vectors": {k: [v.r, v.g, v.b, v.a] for k, v in i.vectors.items()},
            "updated": i.updated,
            "saved": i.path in _saved,
        }
        for i in instances
    ]
    with open(os.environ["HAIRFIT_UNREAL_STUB_OUT"], "w") as f:
        json.dump(state, f)


def log(message):
    print(message)


class EditorAssetLibrary:
    @staticmethod
    def load_asset(asset_path):
        return _assets.get(asset_path)

    @staticmethod
    def does_asset_exist(asset_path):
        return asset_path in _assets

    @staticmethod
    def save_asset(asset_to_save, only_if_is_dirty=True):
        _saved.append(asset_to_save)
        _dump()
        return True


class AssetTools:
    def create_asset(self, asset_name, package_path, asset_class, factory, calling_context="None"):
        assert asset_class is MaterialInstanceConstant, asset_class
        assert isinstance(factory, MaterialInstanceConstantFactoryNew), factory
        instance = _Instance(package_path + "/" + asset_name)
        _assets[instance.path] = instance
        return instance


class AssetToolsHelpers:
    @staticmethod
    def get_asset_tools():
        return AssetTools()


class MaterialEditingLibrary:
    @staticmethod
    def get_scalar_parameter_names(material):
        return [Name(n) for n in material.scalars]

    @staticmethod
    def get_vector_parameter_names(material):
        return [Name(n) for n in material.vectors]

    @staticmethod
    def set_material_instance_parent(instance, new_parent):
        assert isinstance(instance, _Instance) and isinstance(new_parent, _Material)
        instance.parent = new_parent

    @staticmethod
    def set_material_instance_scalar_parameter_value(instance, parameter_name, value, association=None):
        assert isinstance(value, float), value
        instance.scalars[str(parameter_name)] = value
        return True

    @staticmethod
    def set_material_instance_vector_parameter_value(instance, parameter_name, value, association=None):
        assert isinstance(value, LinearColor), value
        instance.vectors[str(parameter_name)] = value
        return True

    @staticmethod
    def update_material_instance(instance):
        instance.updated = True

    @staticmethod
    def get_material_instance_scalar_parameter_value(instance, parameter_name, association=None):
        return instance.scalars[str(parameter_name)]

    @staticmethod
    def get_material_instance_vector_parameter_value(instance, parameter_name, association=None):
        return instance.vectors[str(parameter_name)]
