//! The culling strategy and its parameters on the command line (`StrategyArgs`), shared by
//! `render`, `cull` and `tune`.

use anyhow::{Context, Result, bail};
use clap::ValueEnum;
use manylights_cull::layout::DEFAULT_SLACK;
use manylights_cull::{CullSettings, Slicing, Strategy};

/// `--slices` where none is given.
const DEFAULT_SLICES: u32 = 24;

/// A culling strategy and its parameters.
#[derive(clap::Args, Debug)]
pub(crate) struct StrategyArgs {
    /// Culling strategy (default: tiled-gather).
    #[arg(long, value_enum)]
    pub(crate) strategy: Option<StrategyName>,
    /// Tile side in pixels (8, 16 and 32 are usual; 4..=256 accepted). Default: 16, or 64 for
    /// clustered.
    #[arg(long)]
    pub(crate) tile_size: Option<u32>,
    /// Depth slices of the cluster grid (clustered only; default 24).
    #[arg(long)]
    pub(crate) slices: Option<u32>,
    /// Depth bins of z-binning (zbin only; 1..=1024; default 256).
    #[arg(long)]
    pub(crate) bins: Option<u32>,
    /// Slicing of the cluster grid (clustered), or of z-binning's depth bins (zbin); default
    /// exponential.
    #[arg(long, value_enum)]
    pub(crate) slicing: Option<SlicingName>,
    /// Emit lights only into clusters that hold geometry (clustered only).
    #[arg(long)]
    pub(crate) skip_empty: bool,
    /// 2.5D cells inside each cluster: a light is kept only where its depth extent meets the
    /// 32 cells of the cluster's pixels' depth range that hold pixels (clustered only; needs
    /// the box test).
    #[arg(long)]
    pub(crate) cells: bool,
    /// Keep the clusters' atomic fill order instead of sorting each list into light order
    /// (clustered only; one pass less, images no longer bit-identical across runs).
    #[arg(long)]
    pub(crate) unordered: bool,
    /// Gather and 2.5D: 8 culls lights against coarse tiles of 8 x 8 tiles first, and each tile
    /// tests only its coarse tile's survivors; 0 tests every light at every tile (the paper's
    /// single level; default 8).
    #[arg(long)]
    pub(crate) coarse: Option<u32>,
    /// Conservative slack, relative to each light's distance from the eye.
    #[arg(long, default_value_t = DEFAULT_SLACK)]
    pub(crate) slack: f32,
    /// A deliberate cap on each list's length: lights beyond it are dropped and counted (the
    /// default, none, sizes lists exactly and drops nothing).
    #[arg(long)]
    pub(crate) capacity: Option<u32>,
    /// Tile tests without the box test (each light's sphere against the view-space box of the
    /// tile's frustum, on by default): the side planes alone, for ablations.
    #[arg(long)]
    pub(crate) no_tile_boxes: bool,
}

impl StrategyArgs {
    /// The strategy named by `--strategy`, tiled gather where it is not given.
    fn name(&self) -> StrategyName {
        self.strategy.unwrap_or(StrategyName::TiledGather)
    }

    /// The first option given that only culling reads (`--strategy` and its parameters, a
    /// list cap, the box test's ablation), for an error where nothing culls.
    pub(crate) fn culling_option_given(&self) -> Option<&'static str> {
        [
            ("--strategy", self.strategy.is_some()),
            ("--tile-size", self.tile_size.is_some()),
            ("--slices", self.slices.is_some()),
            ("--bins", self.bins.is_some()),
            ("--slicing", self.slicing.is_some()),
            ("--skip-empty", self.skip_empty),
            ("--cells", self.cells),
            ("--unordered", self.unordered),
            ("--coarse", self.coarse.is_some()),
            ("--capacity", self.capacity.is_some()),
            ("--no-tile-boxes", self.no_tile_boxes),
            ("--slack", self.slack != DEFAULT_SLACK),
        ]
        .into_iter()
        .find_map(|(option, given)| given.then_some(option))
    }

    /// The strategy the options name; an error where an option is given that the strategy does
    /// not read (it would be ignored without a word).
    pub(crate) fn strategy(&self) -> Result<Strategy> {
        self.check_used()?;
        let default_tile = if matches!(self.name(), StrategyName::Clustered) {
            64
        } else {
            16
        };
        let tile_size = self.tile_size.unwrap_or(default_tile);
        let coarse = self.coarse.unwrap_or(manylights_cull::DEFAULT_COARSE);
        let slicing = self.slicing.unwrap_or(SlicingName::Exponential).into();
        let strategy = match self.name() {
            StrategyName::TiledGather => Strategy::TiledGather { tile_size, coarse },
            StrategyName::TiledScatter => Strategy::TiledScatter { tile_size },
            StrategyName::DepthMask => Strategy::DepthMask { tile_size, coarse },
            StrategyName::Clustered => Strategy::Clustered {
                tile_size,
                slices: self.slices.unwrap_or(DEFAULT_SLICES),
                slicing,
                skip_empty: self.skip_empty,
                ordered: !self.unordered,
                cells: self.cells,
            },
            StrategyName::Zbin => Strategy::ZBin {
                tile_size,
                bins: self.bins.unwrap_or(manylights_cull::DEFAULT_ZBINS),
                slicing,
            },
        };
        strategy.validate()?;
        Ok(strategy)
    }

    /// An error naming the first option given that `--strategy` does not read, and the
    /// strategies that do.
    fn check_used(&self) -> Result<()> {
        use StrategyName::{Clustered, DepthMask, TiledGather, Zbin};
        let given: [(&str, bool, &[StrategyName]); 7] = [
            ("--coarse", self.coarse.is_some(), &[TiledGather, DepthMask]),
            ("--slices", self.slices.is_some(), &[Clustered]),
            ("--skip-empty", self.skip_empty, &[Clustered]),
            ("--cells", self.cells, &[Clustered]),
            ("--unordered", self.unordered, &[Clustered]),
            ("--bins", self.bins.is_some(), &[Zbin]),
            ("--slicing", self.slicing.is_some(), &[Clustered, Zbin]),
        ];
        for (option, set, readers) in given {
            if set && !readers.contains(&self.name()) {
                let names: Vec<String> = readers.iter().map(|r| r.cli_name()).collect();
                bail!(
                    "{option} is read only by --strategy {}; --strategy {} would ignore it",
                    names.join(" and "),
                    self.name().cli_name()
                );
            }
        }
        Ok(())
    }

    pub(crate) fn settings(&self, camera: &manylights_scene::Camera) -> Result<CullSettings> {
        let s = CullSettings {
            slack: self.slack,
            capacity: self.capacity,
            tile_boxes: !self.no_tile_boxes,
            ..CullSettings::for_camera(camera)
        };
        s.validate().context("invalid --slack or --capacity")?;
        Ok(s)
    }
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub(crate) enum StrategyName {
    /// Forward+ tiled gather (Harada et al. 2012, 4.1).
    TiledGather,
    /// Forward+ tiled scatter with the GPU radix sort (Harada et al. 2012, 4.2).
    TiledScatter,
    /// 2.5D culling with depth masks (Harada 2012).
    DepthMask,
    /// 3D clusters (Olsson et al. 2012).
    Clustered,
    /// Z-binning with tile bitmasks (Drobot 2017; Unity URP's Forward+).
    #[value(name = "zbin")]
    Zbin,
}

impl StrategyName {
    /// Its `--strategy` value.
    fn cli_name(self) -> String {
        self.to_possible_value()
            .map_or_else(String::new, |v| v.get_name().to_owned())
    }
}

#[derive(Clone, Copy, Debug, ValueEnum)]
pub(crate) enum SlicingName {
    /// Equal depth per slice.
    Linear,
    /// Equal depth ratio per slice.
    Exponential,
}

impl From<SlicingName> for Slicing {
    fn from(s: SlicingName) -> Self {
        match s {
            SlicingName::Linear => Slicing::Linear,
            SlicingName::Exponential => Slicing::Exponential,
        }
    }
}
