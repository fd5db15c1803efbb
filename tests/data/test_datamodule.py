"""The data module: the training loader resumes mid-epoch, and a split is capped to its first clips."""

import torch
from torch.utils.data import Dataset

from keyin.data.brownian import BrownianGenerator
from keyin.data.datamodule import ClipDataModule, split_clips
from keyin.data.generate import generate_dataset


class Numbers(Dataset):
    def __len__(self) -> int:
        return 40

    def __getitem__(self, index: int) -> int:
        return index


def test_a_restored_train_loader_continues_the_epoch_where_it_stopped():
    torch.manual_seed(0)
    loader = ClipDataModule(Numbers(), Numbers(), batch_size=4, num_workers=0).train_dataloader()
    batches = iter(loader)
    seen = [next(batches) for _ in range(3)]
    state = loader.state_dict()
    rest = list(batches)
    torch.manual_seed(123)  # a resumed process has other random state
    restored = ClipDataModule(Numbers(), Numbers(), batch_size=4, num_workers=0).train_dataloader()
    restored.load_state_dict(state)
    continued = list(restored)
    assert [b.tolist() for b in continued] == [b.tolist() for b in rest]
    assert sorted(torch.cat(seen + continued).tolist()) == list(range(40))  # one epoch, nothing repeated


def test_a_file_split_is_capped_to_its_first_clips_like_a_generated_one(tmp_path):
    """scale.val_clips / eval_clips cap file datasets too (pushing validated on all 1000 val clips)."""
    generate_dataset(BrownianGenerator(), tmp_path / "brownian", "brownian", {"val": 5}, 5, 0, progress=False)
    dataset = {"name": "brownian", "train_source": "files", "image_size": 32, "channels": 1, "n_cond": 5,
               "n_future": 30}
    capped = split_clips(dataset, None, "val", 3, tmp_path)
    whole = split_clips(dataset, None, "val", None, tmp_path)
    assert len(capped) == 3 and len(whole) == 5 and len(split_clips(dataset, None, "val", 50, tmp_path)) == 5
    assert torch.equal(capped[2]["frames"], whole[2]["frames"])
