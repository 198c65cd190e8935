;;; tests/editor-offline.el --- tools/luv-physics.el without SLIME, run by tools/editor-test  -*- lexical-binding: t -*-

;; Run in `emacs -Q --batch' with only tools/luv-physics.el loaded (no SLIME on
;; the load path).  LUV_COPY names a copy of physics.org beside a luv-physics.asd.
;; The jumps read the page's text; reloading says what it needs.

;;; Code:

(require 'cl-lib)

(let ((passed 0) (failed 0))
  (cl-flet ((check (name ok &rest detail)
              (if ok
                  (progn (cl-incf passed) (message "editor-test: ok: %s" name))
                (cl-incf failed)
                (message "editor-test: FAILED: %s %S" name detail)))
            (line () (buffer-substring-no-properties (line-beginning-position) (line-end-position))))
    (condition-case err
        (progn
          (check "without SLIME the mode loads and starts" (and (not (featurep 'slime))
                                                                (progn (find-file (getenv "LUV_COPY")) luv-physics-mode)))
          (goto-char (point-min))
          (re-search-forward "^:CUSTOM_ID: BSOZ3U$")
          (cl-letf (((symbol-function 'completing-read)
                     (lambda (_prompt collection &rest _)
                       (car (cl-find-if (lambda (c) (string-prefix-p "definition-anchor " (car c))) collection)))))
            (call-interactively #'luv-physics-definitions))
          (check "without SLIME, anchor -> definition reads the page"
                 (string-prefix-p "(defun definition-anchor (name" (line)) (line))
          (goto-char (point-min))
          (re-search-forward "(step-physics-world w)")
          (backward-char 3)
          (call-interactively #'luv-physics-page-definition)
          (check "without SLIME, symbol -> page reads the page"
                 (string-prefix-p "(defun step-physics-world (world" (line)) (line))
          (check "without SLIME, reloading says what it needs"
                 (string-match-p "needs SLIME"
                                 (condition-case e (progn (luv-physics-reload-section nil) "")
                                   (user-error (error-message-string e))))))
      (error (check "the checks without SLIME ran to the end" nil (error-message-string err)))))
  (message "editor-test: without SLIME %d passed, %d failed" passed failed)
  (kill-emacs (if (and (zerop failed) (> passed 0)) 0 1)))

;;; editor-offline.el ends here
